//! Fault injection settings for the fake printer, their `--faults` syntax, and the seeded
//! random source that makes every faulty run reproducible.

use thiserror::Error;

/// What can go wrong, with rates per line (0.0 to 1.0) and one-shot events by count of
/// executed commands.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Faults {
    /// Host→printer: one byte of a received line is changed (Marlin then sees a checksum or
    /// line-number error).
    pub corrupt: f64,
    /// Printer→host: one byte of a reply is replaced by line noise (a byte ≥ 0x80, as a UART
    /// framing error gives).
    pub corrupt_reply: f64,
    /// A received line is lost entirely.
    pub drop: f64,
    /// The `ok` after an executed command is not sent.
    pub drop_ok: f64,
    /// A good line is refused with `Error:checksum mismatch` and an `ok`, but no `Resend:`.
    pub error: f64,
    /// A good line is refused with a bare request for itself (`Resend:` + `ok`, no error
    /// line), as OctoPrint's virtual printer does on its `resend` error; it is not taken.
    pub spurious_resend: f64,
    /// After a line error, `Resend:` comes without its `ok`.
    pub no_resend_ok: f64,
    /// Before executing a command, the printer reports `echo:busy: processing` a few times.
    pub busy: f64,
    /// After this many executed commands, the board resets (`start`) and forgets its queue.
    pub reset_at: Option<u64>,
    /// After this many executed commands, the firmware halts (`Error:Printer halted...`).
    pub halt_at: Option<u64>,
    /// After this many executed commands, the printer stops answering altogether.
    pub silent_at: Option<u64>,
    /// Reply `ok N<line> P<planner> B<free slots>` (Marlin's ADVANCED_OK).
    pub advanced_ok: bool,
    /// Seed of the random source.
    pub seed: u64,
}

/// How many of each fault the fake printer actually injected, so a test can check that the
/// fault it asked for happened (a job that succeeds proves little if nothing went wrong).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FaultCounts {
    /// Received lines with a byte changed.
    pub corrupt: u64,
    /// Replies with a byte replaced by line noise.
    pub corrupt_reply: u64,
    /// Received lines lost.
    pub drop: u64,
    /// `ok`s not sent.
    pub drop_ok: u64,
    /// Refusals sent without their resend request.
    pub error: u64,
    /// Resend requests for lines already taken.
    pub spurious_resend: u64,
    /// Resend requests sent without their `ok`.
    pub no_resend_ok: u64,
    /// Commands preceded by busy reports.
    pub busy: u64,
    /// Board resets.
    pub reset: u64,
    /// Firmware halts.
    pub halt: u64,
    /// Times the printer went silent.
    pub silent: u64,
}

impl std::fmt::Display for FaultCounts {
    /// `corrupt=12 drop=3 ...`, in the `--faults` key names, the non-zero ones only.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let all = [
            ("corrupt", self.corrupt),
            ("corrupt-reply", self.corrupt_reply),
            ("drop", self.drop),
            ("drop-ok", self.drop_ok),
            ("error", self.error),
            ("spurious-resend", self.spurious_resend),
            ("no-resend-ok", self.no_resend_ok),
            ("busy", self.busy),
            ("reset", self.reset),
            ("halt", self.halt),
            ("silent", self.silent),
        ];
        let shown: Vec<String> = all
            .iter()
            .filter(|(_, n)| *n > 0)
            .map(|(k, n)| format!("{k}={n}"))
            .collect();
        if shown.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&shown.join(" "))
        }
    }
}

/// The `--faults` syntax, for help texts.
pub const FAULTS_HELP: &str = "comma-separated KEY=VALUE: rates per line corrupt=P (host->printer byte), \
corrupt-reply=P (printer->host byte), drop=P (line lost), drop-ok=P, error=P (Error: without Resend), \
spurious-resend=P, no-resend-ok=P (Resend without ok), busy=P; events after N executed commands \
reset-at=N, halt-at=N, silent-at=N; advanced-ok (ok N.. P.. B.. replies); seed=N. \
Example: corrupt=0.01,drop=0.005,reset-at=5000,seed=7";

/// A `--faults` string that does not parse.
#[derive(Debug, Error)]
#[error("fault spec {spec:?}: {reason} (syntax: {FAULTS_HELP})")]
pub struct FaultsError {
    spec: String,
    reason: String,
}

impl Faults {
    /// Parses `corrupt=0.01,drop=0.005,reset-at=5000,seed=7`.
    pub fn parse(spec: &str) -> Result<Faults, FaultsError> {
        let err = |reason: String| FaultsError {
            spec: spec.to_string(),
            reason,
        };
        let mut f = Faults::default();
        for item in spec.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (key, value) = item.split_once('=').unwrap_or((item, ""));
            let rate = || -> Result<f64, FaultsError> {
                let v: f64 = value
                    .parse()
                    .map_err(|_| err(format!("{key}: {value:?} is not a number")))?;
                if !(0.0..=1.0).contains(&v) {
                    return Err(err(format!("{key}: {v} is not a rate between 0 and 1")));
                }
                Ok(v)
            };
            let count = || -> Result<u64, FaultsError> {
                value
                    .parse()
                    .map_err(|_| err(format!("{key}: {value:?} is not a whole number")))
            };
            match key {
                "corrupt" => f.corrupt = rate()?,
                "corrupt-reply" => f.corrupt_reply = rate()?,
                "drop" => f.drop = rate()?,
                "drop-ok" => f.drop_ok = rate()?,
                "error" => f.error = rate()?,
                "spurious-resend" => f.spurious_resend = rate()?,
                "no-resend-ok" => f.no_resend_ok = rate()?,
                "busy" => f.busy = rate()?,
                "reset-at" => f.reset_at = Some(count()?),
                "halt-at" => f.halt_at = Some(count()?),
                "silent-at" => f.silent_at = Some(count()?),
                "seed" => f.seed = count()?,
                "advanced-ok" => f.advanced_ok = true,
                _ => return Err(err(format!("unknown key {key:?}"))),
            }
        }
        Ok(f)
    }
}

/// SplitMix64: tiny, fast, and good enough to pick faults; seeded so runs repeat exactly.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x9e37_79b9_7f4a_7c15)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// True with probability `p`.
    pub fn chance(&mut self, p: f64) -> bool {
        p > 0.0 && (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64 <= p
    }

    /// A number in `0..n` (n > 0).
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_the_documented_example() {
        let f = Faults::parse("corrupt=0.01,drop=0.005,reset-at=5000,seed=7").unwrap();
        assert_eq!(f.corrupt, 0.01);
        assert_eq!(f.drop, 0.005);
        assert_eq!(f.reset_at, Some(5000));
        assert_eq!(f.seed, 7);
        let f = Faults::parse("advanced-ok, busy=0.5").unwrap();
        assert!(f.advanced_ok);
        assert_eq!(f.busy, 0.5);
        assert_eq!(Faults::parse("").unwrap(), Faults::default());
    }

    #[test]
    fn rejects_bad_specs() {
        for bad in ["corrupt=2", "drop=x", "reset-at=-1", "frobnicate=1"] {
            assert!(Faults::parse(bad).is_err(), "{bad}");
        }
    }

    #[test]
    fn rng_is_seeded_and_fair() {
        let mut a = Rng::new(7);
        let mut b = Rng::new(7);
        assert_eq!(a.next_u64(), b.next_u64());
        let hits = (0..10_000).filter(|_| a.chance(0.1)).count();
        assert!((800..1200).contains(&hits), "{hits}");
        assert!(!a.chance(0.0));
    }
}
