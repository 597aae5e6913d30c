//! The options map of modern-library calls: `twist(s, 2)` takes its arguments in order,
//! `linear_sweep(p, 10, #{twist: 90, center: true})` takes the optional ones by name.
//!
//! A library function reads its options key by key and then calls [`Options::finish`]:
//!
//! ```ignore
//! let mut o = Options::new("linear_sweep", map);
//! let twist = o.number("twist")?.unwrap_or(0.0);
//! let center = o.flag("center")?.unwrap_or(false);
//! let method = o.choice("method", &["incremental", "natural"])?;
//! o.finish()?;
//! ```
//!
//! Every key read is remembered, so `finish` knows the function's whole vocabulary without
//! a second list to keep in step: a key the script gave that was never read is an error
//! that names it, the function, the keys it takes, and the nearest one ("did you mean").
//! A value of the wrong type is an error that names the key, the function, what was
//! expected and what was given. Both are typed causes ([`RuntimeCause::UnknownOption`],
//! [`RuntimeCause::OptionType`]), raised at the call's position like any library error.

use rhai::{Array, Dynamic, FnPtr, Map};

use crate::RuntimeCause;
use crate::args::{RhaiResult, as_number, fail_with, type_name};

/// The options a script passed to one call, read key by key.
#[derive(Debug)]
pub struct Options {
    func: &'static str,
    map: Map,
    /// Every key asked for so far, in order: the function's vocabulary.
    known: Vec<&'static str>,
}

impl Options {
    /// The options of a call to `func`.
    pub fn new(func: &'static str, map: Map) -> Options {
        Options {
            func,
            map,
            known: Vec::new(),
        }
    }

    /// No options (the call had no map): every read gives `None`.
    pub fn none(func: &'static str) -> Options {
        Options::new(func, Map::new())
    }

    /// The function these options belong to.
    pub fn function(&self) -> &'static str {
        self.func
    }

    /// The raw value of `key`, if given; for values no typed reader below fits. Use
    /// [`Options::wrong_type`] to refuse one.
    pub fn take(&mut self, key: &'static str) -> Option<Dynamic> {
        if !self.known.contains(&key) {
            self.known.push(key);
        }
        self.map.remove(key)
    }

    /// The error for `key` holding `value` where `expected` was wanted ("a number",
    /// "[x, y, z]", ...).
    pub fn wrong_type(
        &self,
        key: &str,
        expected: &str,
        value: &Dynamic,
    ) -> Box<rhai::EvalAltResult> {
        fail_with(RuntimeCause::OptionType {
            function: self.func.to_string(),
            key: key.to_string(),
            expected: expected.to_string(),
            found: describe(value),
        })
    }

    /// The error for `key` whose value has the right type but is out of range: `why`
    /// says what is allowed ("must be positive").
    pub fn bad_value(&self, key: &str, value: &Dynamic, why: &str) -> Box<rhai::EvalAltResult> {
        fail_with(RuntimeCause::OptionType {
            function: self.func.to_string(),
            key: key.to_string(),
            expected: why.to_string(),
            found: describe(value),
        })
    }

    /// A number (whole or real).
    pub fn number(&mut self, key: &'static str) -> RhaiResult<Option<f64>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => as_number(&v)
                .filter(|n| n.is_finite())
                .map(Some)
                .ok_or_else(|| self.wrong_type(key, "a finite number", &v)),
        }
    }

    /// A whole number.
    pub fn count(&mut self, key: &'static str) -> RhaiResult<Option<i64>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => match (v.as_int(), as_number(&v)) {
                (Ok(i), _) => Ok(Some(i)),
                (_, Some(f)) if f.fract() == 0.0 && f.abs() < 9e15 => Ok(Some(f as i64)),
                _ => Err(self.wrong_type(key, "a whole number", &v)),
            },
        }
    }

    /// `true` or `false`.
    pub fn flag(&mut self, key: &'static str) -> RhaiResult<Option<bool>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => v
                .as_bool()
                .map(Some)
                .map_err(|_| self.wrong_type(key, "true or false", &v)),
        }
    }

    /// A string.
    pub fn string(&mut self, key: &'static str) -> RhaiResult<Option<String>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => match v.clone().into_immutable_string() {
                Ok(s) => Ok(Some(s.to_string())),
                Err(_) => Err(self.wrong_type(key, "a string", &v)),
            },
        }
    }

    /// One of a fixed set of names; the error lists them.
    pub fn choice(
        &mut self,
        key: &'static str,
        names: &[&'static str],
    ) -> RhaiResult<Option<&'static str>> {
        let expected = || {
            let quoted: Vec<String> = names.iter().map(|n| format!("\"{n}\"")).collect();
            format!("one of {}", quoted.join(", "))
        };
        match self.take(key) {
            None => Ok(None),
            Some(v) => {
                let found = v
                    .clone()
                    .into_immutable_string()
                    .ok()
                    .and_then(|s| names.iter().find(|n| **n == s.as_str()).copied());
                found
                    .map(Some)
                    .ok_or_else(|| self.wrong_type(key, &expected(), &v))
            }
        }
    }

    /// An array of exactly `N` numbers (`[x, y, z]` for N = 3).
    pub fn vector<const N: usize>(&mut self, key: &'static str) -> RhaiResult<Option<[f64; N]>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => vector::<N>(&v)
                .map(Some)
                .ok_or_else(|| self.wrong_type(key, &vector_name(N), &v)),
        }
    }

    /// A number `k` (read as `[k; N]`) or an array of `N` numbers: a uniform or
    /// per-axis value such as a scale.
    pub fn number_or_vector<const N: usize>(
        &mut self,
        key: &'static str,
    ) -> RhaiResult<Option<[f64; N]>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => {
                if let Some(k) = as_number(&v).filter(|k| k.is_finite()) {
                    return Ok(Some([k; N]));
                }
                vector::<N>(&v).map(Some).ok_or_else(|| {
                    self.wrong_type(key, &format!("a number or {}", vector_name(N)), &v)
                })
            }
        }
    }

    /// An array of any length (its elements are the caller's to check).
    pub fn array(&mut self, key: &'static str) -> RhaiResult<Option<Array>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => match v.clone().try_cast::<Array>() {
                Some(a) => Ok(Some(a)),
                None => Err(self.wrong_type(key, "an array", &v)),
            },
        }
    }

    /// A function (a closure `|s| ...` or `Fn("name")`).
    pub fn function_value(&mut self, key: &'static str) -> RhaiResult<Option<FnPtr>> {
        match self.take(key) {
            None => Ok(None),
            Some(v) => match v.clone().try_cast::<FnPtr>() {
                Some(f) => Ok(Some(f)),
                None => Err(self.wrong_type(key, "a function", &v)),
            },
        }
    }

    /// Checks that every key the script gave was read: the first one that was not is an
    /// error naming it, the keys this function takes and the nearest of them.
    pub fn finish(self) -> RhaiResult<()> {
        let Some(key) = self.map.keys().next() else {
            return Ok(());
        };
        let key = key.to_string();
        let suggestion = self
            .known
            .iter()
            .map(|k| (strsim::levenshtein(&key.to_lowercase(), k), *k))
            .filter(|(d, k)| *d <= 2.min(k.len().div_ceil(2)))
            .min_by_key(|(d, _)| *d)
            .map(|(_, k)| k.to_string());
        Err(fail_with(RuntimeCause::UnknownOption {
            function: self.func.to_string(),
            key,
            known: self.known.iter().map(|k| k.to_string()).collect(),
            suggestion,
        }))
    }
}

fn vector<const N: usize>(v: &Dynamic) -> Option<[f64; N]> {
    let a = v.clone().try_cast::<Array>()?;
    if a.len() != N {
        return None;
    }
    let mut out = [0.0; N];
    for (o, d) in out.iter_mut().zip(&a) {
        *o = as_number(d).filter(|n| n.is_finite())?;
    }
    Some(out)
}

fn vector_name(n: usize) -> String {
    match n {
        2 => "[x, y]".to_string(),
        3 => "[x, y, z]".to_string(),
        _ => format!("an array of {n} numbers"),
    }
}

/// What a value is, for messages: its kind, and the value itself when it is short.
fn describe(v: &Dynamic) -> String {
    let kind = type_name(v);
    if let Some(n) = as_number(v) {
        return format!("{kind} ({n})");
    }
    if let Ok(s) = v.clone().into_immutable_string()
        && s.chars().count() <= 40
    {
        return format!("{kind} (\"{s}\")");
    }
    if let Ok(b) = v.as_bool() {
        return format!("{kind} ({b})");
    }
    kind.to_string()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rhai::Engine;

    /// A test function with options: `probe(#{..})` returns what it read, as a string.
    fn engine() -> Engine {
        let mut e = Engine::new();
        e.register_fn("probe", |map: Map| -> RhaiResult<String> {
            let mut o = Options::new("probe", map);
            let twist = o.number("twist")?;
            let n = o.count("slices")?;
            let closed = o.flag("closed")?;
            let method = o.choice("method", &["incremental", "natural"])?;
            let normal = o.vector::<3>("normal")?;
            let scale = o.number_or_vector::<2>("scale")?;
            o.finish()?;
            Ok(format!(
                "{twist:?} {n:?} {closed:?} {method:?} {normal:?} {scale:?}"
            ))
        });
        e
    }

    fn cause(script: &str) -> RuntimeCause {
        match *engine().eval::<String>(script).expect_err("fails") {
            rhai::EvalAltResult::ErrorRuntime(v, _) => v.try_cast::<RuntimeCause>().expect("typed"),
            other => panic!("unexpected error {other}"),
        }
    }

    #[test]
    fn reads_every_kind() {
        let out = engine()
            .eval::<String>(
                r#"probe(#{twist: 90, slices: 12.0, closed: true, method: "natural",
                           normal: [0, 0, 1], scale: 2})"#,
            )
            .expect("runs");
        assert_eq!(
            out,
            "Some(90.0) Some(12) Some(true) Some(\"natural\") Some([0.0, 0.0, 1.0]) Some([2.0, 2.0])"
        );
        let out = engine().eval::<String>("probe(#{})").expect("runs");
        assert_eq!(out, "None None None None None None");
        let out = engine()
            .eval::<String>("probe(#{scale: [1, 0.5]})")
            .expect("runs");
        assert!(out.ends_with("Some([1.0, 0.5])"), "{out}");
    }

    #[test]
    fn an_unknown_key_is_named_with_the_known_ones() {
        let c = cause("probe(#{twsit: 90})");
        assert_eq!(
            c,
            RuntimeCause::UnknownOption {
                function: "probe".into(),
                key: "twsit".into(),
                known: ["twist", "slices", "closed", "method", "normal", "scale"]
                    .map(String::from)
                    .to_vec(),
                suggestion: Some("twist".into()),
            }
        );
        let text = c.to_string();
        for w in ["probe", "`twsit`", "did you mean `twist`", "slices"] {
            assert!(text.contains(w), "{w:?} not in {text}");
        }
        let RuntimeCause::UnknownOption { suggestion, .. } = cause("probe(#{colour: 1})") else {
            panic!("wrong cause")
        };
        assert_eq!(suggestion, None, "no near name");
    }

    #[test]
    fn a_wrong_type_names_key_function_and_both_types() {
        let cases = [
            (
                "probe(#{twist: \"a lot\"})",
                "twist",
                "a finite number",
                "a string (\"a lot\")",
            ),
            (
                "probe(#{slices: 2.5})",
                "slices",
                "a whole number",
                "a number (2.5)",
            ),
            (
                "probe(#{closed: 1})",
                "closed",
                "true or false",
                "a number (1)",
            ),
            (
                "probe(#{method: \"magic\"})",
                "method",
                "one of \"incremental\", \"natural\"",
                "a string (\"magic\")",
            ),
            (
                "probe(#{normal: [0, 1]})",
                "normal",
                "[x, y, z]",
                "an array",
            ),
            (
                "probe(#{scale: \"big\"})",
                "scale",
                "a number or [x, y]",
                "a string (\"big\")",
            ),
        ];
        for (script, key, expected, found) in cases {
            assert_eq!(
                cause(script),
                RuntimeCause::OptionType {
                    function: "probe".into(),
                    key: key.into(),
                    expected: expected.into(),
                    found: found.into(),
                },
                "{script}"
            );
        }
        let text = cause("probe(#{twist: ()})").to_string();
        assert!(
            text.contains("probe") && text.contains("`twist`") && text.contains("a finite number"),
            "{text}"
        );
    }
}
