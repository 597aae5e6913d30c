//! Compares isoforge's own sin/cos/exp enclosures with inari's gmp-backed ones.
use inari::Interval;
use isoforge_field::eval::enclose;
use std::hint::black_box;
use std::time::Instant;

fn main() {
    let n = 200_000;
    let boxes: Vec<Interval> = (0..n)
        .map(|i| {
            let lo = ((i * 7919) % 20000) as f64 / 1000.0 - 10.0;
            let w = [1e-6, 1e-3, 0.05, 0.5][i % 4];
            Interval::try_from((lo, lo + w)).unwrap()
        })
        .collect();
    for (name, ours, theirs) in [
        ("sin", enclose::sin as fn(Interval) -> (Interval, bool), Interval::sin as fn(Interval) -> Interval),
        ("cos", enclose::cos, Interval::cos),
        ("exp", enclose::exp, Interval::exp),
    ] {
        // Correctness cross-check: ours must contain theirs (theirs is tight, ours widened).
        let mut wider = 0.0;
        for b in &boxes {
            let (o, _) = ours(*b);
            let t = theirs(*b);
            assert!(o.inf() <= t.inf() && o.sup() >= t.sup(), "{name}: ours {o:?} misses theirs {t:?} on {b:?}");
            wider += (o.wid() - t.wid()).max(0.0) / t.wid().max(1e-300);
        }
        let mut best = [f64::INFINITY; 2];
        for _ in 0..5 {
            let s = Instant::now();
            let mut acc = 0.0;
            for b in &boxes { acc += ours(black_box(*b)).0.sup(); }
            black_box(acc);
            best[0] = best[0].min(s.elapsed().as_secs_f64() / n as f64);
            let s = Instant::now();
            let mut acc = 0.0;
            for b in &boxes { acc += theirs(black_box(*b)).sup(); }
            black_box(acc);
            best[1] = best[1].min(s.elapsed().as_secs_f64() / n as f64);
        }
        println!("{name}: ours {:.1} ns, inari+gmp {:.1} ns, mean relative extra width {:.2e}",
                 best[0] * 1e9, best[1] * 1e9, wider / n as f64);
    }
}
