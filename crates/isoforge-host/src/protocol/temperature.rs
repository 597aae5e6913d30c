//! Temperature reports: `T:200.0 /200.0 B:60.0 /60.0 @:0 B@:0` (Marlin's M105 reply and
//! M155 auto-report), multi-extruder `T0:200.0 /200.0 T1:...`, and the looser
//! `T:200.00/ 200.00` some firmwares print.

/// One heater's reading.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Reading {
    /// Measured temperature, °C.
    pub actual: f64,
    /// Target, °C, when the report gives one.
    pub target: Option<f64>,
}

/// The heaters named in one report.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Temperatures {
    /// Hotends in tool order (`T0`, `T1`, ...; a lone `T` is tool 0).
    pub tools: Vec<Reading>,
    /// The bed (`B`).
    pub bed: Option<Reading>,
    /// The chamber (`C`).
    pub chamber: Option<Reading>,
}

impl Temperatures {
    /// Parses the temperatures in a line; `None` when it names no heater.
    pub fn parse(line: &str) -> Option<Temperatures> {
        let mut t = Temperatures::default();
        let mut numbered: Vec<(usize, Reading)> = Vec::new();
        let mut plain_t: Option<Reading> = None;
        let bytes = line.as_bytes();
        let mut i = 0;
        while i < bytes.len() {
            // A heater key starts a word: T, T<n>, B, C, followed by ':'.
            let at_word_start = i == 0 || bytes[i - 1] == b' ';
            if !at_word_start {
                i += 1;
                continue;
            }
            let word_end = line[i..].find(' ').map_or(line.len(), |p| i + p);
            let Some(key_end) = line[i..word_end].find(':').map(|p| i + p) else {
                i = word_end + 1;
                continue;
            };
            let key = &line[i..key_end];
            let (reading, next) = parse_reading(line, key_end + 1);
            match (key, reading) {
                ("T", Some(r)) => plain_t = Some(r),
                ("B", Some(r)) => t.bed = Some(r),
                ("C", Some(r)) => t.chamber = Some(r),
                (k, Some(r)) if k.len() > 1 && k.starts_with('T') => {
                    if let Ok(n) = k[1..].parse::<usize>() {
                        numbered.push((n, r));
                    }
                }
                _ => {}
            }
            i = next.max(i + 1);
        }
        if numbered.is_empty() {
            t.tools.extend(plain_t);
        } else {
            numbered.sort_by_key(|(n, _)| *n);
            t.tools = numbered.into_iter().map(|(_, r)| r).collect();
        }
        if t.tools.is_empty() && t.bed.is_none() && t.chamber.is_none() {
            None
        } else {
            Some(t)
        }
    }
}

/// Reads `200.0 /200.0`, `200.0/ 200.0` or `200.0` at `start`; returns the reading and where
/// parsing stopped.
fn parse_reading(line: &str, start: usize) -> (Option<Reading>, usize) {
    let (actual, mut pos) = number_at(line, start);
    let Some(actual) = actual else {
        return (None, pos);
    };
    let rest = &line[pos..];
    let trimmed = rest.trim_start();
    let mut target = None;
    if let Some(after_slash) = trimmed.strip_prefix('/') {
        let slash_at = line.len() - after_slash.len();
        let (t, p) = number_at(line, slash_at);
        if t.is_some() {
            target = t;
            pos = p;
        }
    }
    (Some(Reading { actual, target }), pos)
}

/// A decimal number at `start` after optional spaces.
fn number_at(line: &str, start: usize) -> (Option<f64>, usize) {
    let bytes = line.as_bytes();
    let mut i = start;
    while i < bytes.len() && bytes[i] == b' ' {
        i += 1;
    }
    let num_start = i;
    while i < bytes.len() && (bytes[i].is_ascii_digit() || matches!(bytes[i], b'.' | b'-')) {
        i += 1;
    }
    (line[num_start..i].parse().ok(), i)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn r(actual: f64, target: f64) -> Reading {
        Reading {
            actual,
            target: Some(target),
        }
    }

    #[test]
    fn marlin_m105_reply() {
        let t = Temperatures::parse("ok T:200.0 /200.0 B:60.0 /60.0 @:0 B@:0").unwrap();
        assert_eq!(t.tools, [r(200.0, 200.0)]);
        assert_eq!(t.bed, Some(r(60.0, 60.0)));
    }

    #[test]
    fn auto_report_with_leading_space() {
        let t = Temperatures::parse(" T:21.3 /0.0 B:22.1 /0.0 @:0 B@:0").unwrap();
        assert_eq!(t.tools, [r(21.3, 0.0)]);
        assert_eq!(t.bed, Some(r(22.1, 0.0)));
    }

    #[test]
    fn multi_extruder() {
        let t = Temperatures::parse(
            "ok T:190.0 /200.0 B:55.0 /60.0 T0:190.0 /200.0 T1:25.0 /0.0 @:0 B@:0 @0:0 @1:0",
        )
        .unwrap();
        assert_eq!(t.tools, [r(190.0, 200.0), r(25.0, 0.0)]);
    }

    #[test]
    fn loose_form() {
        let t = Temperatures::parse("T:200.00/ 200.00 B:60.00/ 60.00").unwrap();
        assert_eq!(t.tools, [r(200.0, 200.0)]);
        assert_eq!(t.bed, Some(r(60.0, 60.0)));
    }

    #[test]
    fn heating_report_without_target() {
        let t = Temperatures::parse(" T:150.2 E:0 W:?").unwrap();
        assert_eq!(
            t.tools,
            [Reading {
                actual: 150.2,
                target: None
            }]
        );
    }

    #[test]
    fn not_a_temperature_line() {
        assert_eq!(Temperatures::parse("ok"), None);
        assert_eq!(Temperatures::parse("echo:busy: processing"), None);
        assert_eq!(Temperatures::parse("Resend: 12"), None);
    }
}
