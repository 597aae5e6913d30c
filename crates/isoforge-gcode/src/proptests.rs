//! Laws of the tokenizer and the machine under random input.

use proptest::prelude::*;

use crate::{Command, Effect, Machine, frame, framing, parse_line};

/// A command as a slicer might write it, and the values it carries.
fn command() -> impl Strategy<Value = (String, char, u32, Vec<(char, f64)>)> {
    let code = prop_oneof![
        (
            Just('G'),
            prop_oneof![Just(0u32), Just(1), Just(28), Just(90), Just(91), Just(92)]
        ),
        (
            Just('M'),
            prop_oneof![Just(82u32), Just(83), Just(104), Just(106), Just(140)]
        ),
    ];
    let param = (
        prop_oneof![
            Just('X'),
            Just('Y'),
            Just('Z'),
            Just('E'),
            Just('F'),
            Just('S')
        ],
        -100_000i64..100_000,
    );
    (
        code,
        prop::collection::vec(param, 0..5),
        any::<bool>(),
        any::<bool>(),
    )
        .prop_map(|((letter, number), params, spaced, leading_zero)| {
            let mut text = if leading_zero && number < 10 {
                format!("{letter}0{number}")
            } else {
                format!("{letter}{number}")
            };
            let mut values = Vec::new();
            for (l, v) in params {
                let v = v as f64 / 1000.0;
                if values.iter().any(|(seen, _)| *seen == l) {
                    continue;
                }
                if spaced {
                    text.push(' ');
                }
                text.push_str(&format!("{l}{v}"));
                values.push((l, v));
            }
            (text, letter, number, values)
        })
}

proptest! {
    #[test]
    fn what_is_written_is_read_back((text, letter, number, values) in command(), n in 0u64..1_000_000) {
        let framed = frame(n, &text);
        let raw = format!("{framed} ; note");
        let line = parse_line(&raw).unwrap();
        prop_assert_eq!(line.number, Some(n));
        prop_assert_eq!(line.checksum, Some(line.computed));
        prop_assert_eq!(line.comment, Some("note"));
        let cmd = line.command.unwrap();
        prop_assert!(cmd.code.is(letter, number));
        for (l, v) in values {
            prop_assert_eq!(cmd.get(l), Some(v));
        }
    }

    #[test]
    fn any_text_is_read_or_refused_without_panic(raw in ".{0,80}") {
        let _ = parse_line(&raw);
        let f = framing(&raw);
        prop_assert!(f.body.len() <= raw.len());
    }

    #[test]
    fn one_changed_byte_breaks_the_checksum((text, ..) in command(), n in 0u64..1000, at in any::<prop::sample::Index>(), bit in 0u8..7) {
        let framed = frame(n, &text);
        let star = framed.rfind('*').unwrap();
        let i = at.index(star);
        let mut bytes = framed.into_bytes();
        bytes[i] ^= 1 << bit;
        // A flipped bit that makes a `*` or a `;` changes where the framing ends; every
        // other flip must be caught by the checksum.
        prop_assume!(!bytes[..star].contains(&b'*') && !bytes[..star].contains(&b';'));
        let damaged = String::from_utf8_lossy(&bytes).into_owned();
        prop_assert!(!framing(&damaged).checksum_matches());
    }

    #[test]
    fn relative_moves_sum(steps in prop::collection::vec((-50i32..50, -50i32..50, 0i32..5), 1..20)) {
        let mut m = Machine::default();
        let mut run = |t: &str| m.apply(&Command::parse(t).unwrap().unwrap());
        run("G28");
        run("G91");
        let (mut x, mut y, mut e) = (0.0, 0.0, 0.0);
        for (dx, dy, de) in steps {
            let (dx, dy, de) = (f64::from(dx) / 10.0, f64::from(dy) / 10.0, f64::from(de) / 10.0);
            let Effect::Move(mv) = run(&format!("G1 X{dx} Y{dy} E{de}")) else {
                return Err(TestCaseError::fail("not a move"));
            };
            prop_assert!((mv.e - de).abs() < 1e-12);
            x += dx;
            y += dy;
            e += de;
        }
        prop_assert!((m.position[0].unwrap() - x).abs() < 1e-9);
        prop_assert!((m.position[1].unwrap() - y).abs() < 1e-9);
        prop_assert!((m.e - e).abs() < 1e-9);
    }
}
