//! Streaming speed against the fake printer on a pty.
//!
//! - `instant`: the fake executes instantly, so the figure is the protocol's latency bound:
//!   windowed streaming (default window 3, and ADVANCED_OK) against ping-pong (`--window 1`).
//! - `baud_250000`: the fake moves bytes no faster than a 250000-baud link (25,000 bytes/s);
//!   divan's bytes/s divided by 25,000 is the share of the link's capacity used.

use std::sync::LazyLock;

use divan::counter::{BytesCount, ItemsCount};
use isoforge_host::fake::{FakeConfig, FakePrinter, Faults, FirmwareConfig};
use isoforge_host::gcode::{self, Program};
use isoforge_host::protocol::Config;
use isoforge_host::streamer::{self, Control, Job};

fn main() {
    divan::main();
}

static SMALL: LazyLock<Program> = LazyLock::new(|| job(10_000));
static LINK: LazyLock<Program> = LazyLock::new(|| job(4_000));

fn job(n: usize) -> Program {
    gcode::parse(&isoforge_host::sample::vase_with_commands(n)).expect("sample parses")
}

/// Bytes on the wire for a clean run: every framed line, M110 included.
fn framed_bytes(p: &Program) -> u64 {
    let mut n = gcode::frame(0, "M110 N0", 0).map_or(0, |s| s.len()) as u64;
    for (i, c) in p.commands.iter().enumerate() {
        n += gcode::frame(i as u64 + 1, &c.text, c.source_line).map_or(0, |s| s.len()) as u64;
    }
    n
}

fn stream(program: &Program, cfg: Config, baud: Option<u32>, advanced_ok: bool) {
    let printer = FakePrinter::spawn(FakeConfig {
        firmware: FirmwareConfig {
            faults: Faults {
                advanced_ok,
                ..Faults::default()
            },
            ..FirmwareConfig::default()
        },
        baud,
        ..FakeConfig::default()
    })
    .expect("a pty");
    let mut port = streamer::open_port(printer.path(), 250_000).expect("open");
    let job = Job {
        program,
        start: 0,
        prelude: vec![],
        journal: None,
    };
    let report = streamer::stream(&mut *port, job, cfg, &Control::new(), |_| {});
    assert!(report.completed, "{:?}", report.error);
}

mod instant {
    use super::*;

    #[divan::bench(sample_count = 5, sample_size = 1)]
    fn ping_pong(b: divan::Bencher) {
        let p = &*SMALL;
        let cfg = Config {
            window: 1,
            ..Config::default()
        };
        b.counter(ItemsCount::new(p.commands.len()))
            .bench(|| stream(p, cfg.clone(), None, false));
    }

    #[divan::bench(sample_count = 5, sample_size = 1)]
    fn windowed(b: divan::Bencher) {
        let p = &*SMALL;
        b.counter(ItemsCount::new(p.commands.len()))
            .bench(|| stream(p, Config::default(), None, false));
    }

    #[divan::bench(sample_count = 5, sample_size = 1)]
    fn advanced_ok(b: divan::Bencher) {
        let p = &*SMALL;
        b.counter(ItemsCount::new(p.commands.len()))
            .bench(|| stream(p, Config::default(), None, true));
    }
}

mod baud_250000 {
    use super::*;

    #[divan::bench(sample_count = 3, sample_size = 1)]
    fn windowed(b: divan::Bencher) {
        let p = &*LINK;
        b.counter(BytesCount::new(framed_bytes(p)))
            .bench(|| stream(p, Config::default(), Some(250_000), false));
    }

    #[divan::bench(sample_count = 3, sample_size = 1)]
    fn ping_pong(b: divan::Bencher) {
        let p = &*LINK;
        let cfg = Config {
            window: 1,
            ..Config::default()
        };
        b.counter(BytesCount::new(framed_bytes(p)))
            .bench(|| stream(p, cfg.clone(), Some(250_000), false));
    }
}
