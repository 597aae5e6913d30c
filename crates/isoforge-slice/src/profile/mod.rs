//! Printer profiles: a flat TOML table of settings, overridden key by key (`KEY=VALUE`), read
//! by serde into typed settings for filament printers ([`FdmSettings`]) or resin printers
//! ([`ResinSettings`]) and validated against the physical ranges of [`keys::KEYS`].
//!
//! Every value remembers where it came from (file and line, or the override), so an error
//! names the key, the value, the allowed range and that origin. Every key the chosen output
//! needs must be present: a missing key is an error, never a silent default.

mod error;
pub mod keys;
mod settings;
mod template;

use std::collections::BTreeMap;
use std::path::Path;

pub use error::{Origin, ProfileError, ProfileErrorKind};
pub use keys::UsedBy;
pub use settings::{
    DisplayOrientation, FdmSettings, InfillPattern, ResinSettings, SupportStyle, Technology,
    TopFillPattern,
};
pub use template::PLACEHOLDERS;

pub(crate) use template::fill as fill_template;

/// One value of a profile, and where it came from.
#[derive(Clone, Debug)]
struct Entry {
    value: toml::Value,
    origin: Origin,
}

/// A profile as read: its values by key with their origins, before they are typed.
#[derive(Clone, Debug)]
pub struct Profile {
    /// Where the profile itself came from (for keys it lacks).
    origin: Origin,
    technology: Technology,
    entries: BTreeMap<String, Entry>,
}

impl Profile {
    /// Parses a profile from TOML text; `path` names it in errors.
    pub fn parse(text: &str, path: &str) -> Result<Profile, ProfileError> {
        let file = Origin::File {
            path: path.to_string(),
            line: None,
        };
        let table: toml::Table = text.parse().map_err(|e: toml::de::Error| {
            let line = e.span().map(|s| line_of(text, s.start));
            ProfileError {
                origin: Some(Origin::File {
                    path: path.to_string(),
                    line,
                }),
                kind: ProfileErrorKind::Toml(e.message().to_string()),
            }
        })?;
        let mut profile = Profile {
            origin: file,
            technology: Technology::Fdm,
            entries: BTreeMap::new(),
        };
        for (key, value) in table {
            let origin = Origin::File {
                path: path.to_string(),
                line: key_line(text, &key),
            };
            profile.insert(key, value, origin)?;
        }
        Ok(profile)
    }

    /// Reads a profile file.
    pub fn load(path: &Path) -> Result<Profile, ProfileError> {
        let text = isoforge_output::read_input_to_string(path).map_err(|e| ProfileError {
            origin: Some(Origin::File {
                path: path.display().to_string(),
                line: None,
            }),
            kind: ProfileErrorKind::Read(e),
        })?;
        Profile::parse(&text, &path.display().to_string())
    }

    /// The built-in generic 220×220 Marlin profile (fixtures/printers/generic_marlin_220.toml).
    pub fn default_fdm() -> Profile {
        Profile::builtin(
            include_str!("../../../../fixtures/printers/generic_marlin_220.toml"),
            "generic_marlin_220",
        )
    }

    /// The built-in resin profile (fixtures/printers/prusa_sl1.toml).
    pub fn default_resin() -> Profile {
        Profile::builtin(
            include_str!("../../../../fixtures/printers/prusa_sl1.toml"),
            "prusa_sl1",
        )
    }

    fn builtin(text: &str, name: &'static str) -> Profile {
        // The built-in texts are tested to parse and validate (profile::tests); were one not
        // to, every key would be reported missing, naming the built-in profile.
        let origin = Origin::Builtin { name };
        match Profile::parse(text, name) {
            Ok(mut p) => {
                p.origin = origin.clone();
                for e in p.entries.values_mut() {
                    e.origin = origin.clone();
                }
                p
            }
            Err(_) => Profile {
                origin,
                technology: Technology::Fdm,
                entries: BTreeMap::new(),
            },
        }
    }

    /// The kind of printer the profile is for (`technology`, filament when absent).
    pub fn technology(&self) -> Technology {
        self.technology
    }

    /// Where the profile came from.
    pub fn origin(&self) -> &Origin {
        &self.origin
    }

    /// A key's value as written, if the profile has it.
    pub fn raw(&self, key: &str) -> Option<&toml::Value> {
        self.entries.get(key).map(|e| &e.value)
    }

    /// Applies one `KEY=VALUE` override. VALUE is TOML (`0.2`, `"gyroid"`, `[200, 200]`),
    /// or bare text for text keys, or comma-separated numbers for a pair. The key must be
    /// known and a number within its range; the whole profile is checked when it is typed.
    pub fn set(&mut self, assignment: &str) -> Result<(), ProfileError> {
        let origin = Origin::Override {
            assignment: assignment.to_string(),
        };
        let Some((key, value)) = assignment.split_once('=') else {
            return Err(ProfileError::new(ProfileErrorKind::OverrideSyntax).at(origin));
        };
        let key = key.trim();
        if key.is_empty() {
            return Err(ProfileError::new(ProfileErrorKind::OverrideSyntax).at(origin));
        }
        self.insert(key.to_string(), override_value(value.trim()), origin)
    }

    /// Adds or replaces a value: the key must be known and a number within its range.
    fn insert(
        &mut self,
        key: String,
        value: toml::Value,
        origin: Origin,
    ) -> Result<(), ProfileError> {
        let fail = |kind| ProfileError::new(kind).at(origin.clone());
        let Some(spec) = keys::spec(&key) else {
            return Err(fail(ProfileErrorKind::UnknownKey {
                suggestion: keys::suggestion(&key),
                key,
            }));
        };
        let value = if spec.range.is_some_and(|r| r.whole) {
            whole_numbers(value)
        } else {
            value
        };
        settings::check_value(spec.key, &value).map_err(fail)?;
        if spec.key == "technology" {
            self.technology = typed(value.clone(), spec.key).map_err(fail)?;
        }
        self.entries.insert(key, Entry { value, origin });
        Ok(())
    }

    /// The filament-printer settings: every key they need present, typed and valid.
    pub fn fdm(&self) -> Result<FdmSettings, ProfileError> {
        let s: FdmSettings = self.typed_settings(Technology::Fdm)?;
        s.validate().map_err(|e| self.locate(e))?;
        Ok(s)
    }

    /// The resin-printer settings: every key they need present, typed and valid.
    pub fn resin(&self) -> Result<ResinSettings, ProfileError> {
        let s: ResinSettings = self.typed_settings(Technology::Resin)?;
        s.validate().map_err(|e| self.locate(e))?;
        Ok(s)
    }

    /// The entries of `technology` deserialized into `T`, after checking that none is for
    /// the other technology and none that `T` needs is missing.
    fn typed_settings<T: serde::de::DeserializeOwned>(
        &self,
        technology: Technology,
    ) -> Result<T, ProfileError> {
        if self.technology != technology {
            let origin = self
                .entries
                .get("technology")
                .map_or_else(|| self.origin.clone(), |e| e.origin.clone());
            return Err(ProfileError::new(ProfileErrorKind::WrongTechnology {
                wanted: technology,
                found: self.technology,
            })
            .at(origin));
        }
        let mut table = toml::Table::new();
        for (key, entry) in &self.entries {
            let Some(spec) = keys::spec(key) else {
                continue;
            };
            if spec.used_by == UsedBy::Profile {
                continue;
            }
            if !spec.used_by.includes(technology) {
                let key_technology = match technology {
                    Technology::Fdm => Technology::Resin,
                    Technology::Resin => Technology::Fdm,
                };
                return Err(ProfileError::new(ProfileErrorKind::OtherTechnology {
                    key: key.clone(),
                    key_technology,
                    technology,
                })
                .at(entry.origin.clone()));
            }
            table.insert(key.clone(), entry.value.clone());
        }
        if let Some(spec) = keys::KEYS.iter().find(|s| {
            s.used_by != UsedBy::Profile
                && s.used_by.includes(technology)
                && !table.contains_key(s.key)
        }) {
            return Err(
                ProfileError::new(ProfileErrorKind::Missing { spec }).at(self.origin.clone())
            );
        }
        serde_path_to_error::deserialize(toml::Value::Table(table)).map_err(|e| {
            let key = e.path().to_string();
            let message = e.inner().message().to_string();
            let origin = self
                .entries
                .get(&key)
                .map_or_else(|| self.origin.clone(), |en| en.origin.clone());
            ProfileError::new(ProfileErrorKind::Invalid { key, message }).at(origin)
        })
    }

    /// The error with the origin of the key it names (or of the profile).
    fn locate(&self, e: ProfileError) -> ProfileError {
        let origin = e
            .kind
            .key()
            .and_then(|k| self.entries.get(k))
            .map_or_else(|| self.origin.clone(), |en| en.origin.clone());
        e.at(origin)
    }
}

/// A value deserialized on its own, as a key of that name.
fn typed<T: serde::de::DeserializeOwned>(
    value: toml::Value,
    key: &str,
) -> Result<T, ProfileErrorKind> {
    T::deserialize(value).map_err(|e| ProfileErrorKind::Invalid {
        key: key.to_string(),
        message: e.message().to_string(),
    })
}

/// Whole floats (`3.0`) as integers, so a count may be written either way.
fn whole_numbers(value: toml::Value) -> toml::Value {
    match value {
        toml::Value::Float(f) if f.fract() == 0.0 && f.abs() < 1e15 => {
            toml::Value::Integer(f as i64)
        }
        toml::Value::Array(items) => {
            toml::Value::Array(items.into_iter().map(whole_numbers).collect())
        }
        other => other,
    }
}

/// An override's value: TOML if it is TOML, else comma-separated numbers as a list, else
/// text (with `\n` standing for a line break, for templates).
fn override_value(text: &str) -> toml::Value {
    if let Ok(mut t) = format!("v = {text}").parse::<toml::Table>()
        && let Some(v) = t.remove("v")
    {
        return v;
    }
    let nums: Option<Vec<toml::Value>> = text
        .split(',')
        .map(|s| s.trim().parse::<f64>().ok().map(toml::Value::Float))
        .collect();
    match nums {
        Some(n) if n.len() > 1 => toml::Value::Array(n),
        _ => toml::Value::String(text.replace("\\n", "\n")),
    }
}

/// The 1-based line of a byte offset.
fn line_of(text: &str, offset: usize) -> usize {
    1 + text.as_bytes()[..offset.min(text.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
}

/// The line where a top-level `key = ...` is written, if it can be found.
fn key_line(text: &str, key: &str) -> Option<usize> {
    text.lines()
        .position(|l| {
            let l = l.trim_start();
            let l = l.strip_prefix(key).or_else(|| {
                l.strip_prefix('"')
                    .and_then(|r| r.strip_prefix(key))
                    .and_then(|r| r.strip_prefix('"'))
            });
            l.is_some_and(|r| r.trim_start().starts_with('='))
        })
        .map(|i| i + 1)
}

#[cfg(test)]
mod tests;
