//! The options of the requests: the errors that name them as the command line and Python do, and
//! how text and numbers from either become typed values.
//!
//! Every option has one name, in `snake_case`: the command line writes it `--select-folds`,
//! Python `select_folds=`. A request is read from a JSON object of these names
//! ([`from_object`]): an unknown name is refused with the names it may have meant, and a bad
//! value is refused with its option's name, never with a position in a text.

use std::fmt;
use std::str::FromStr;

use serde::de::DeserializeOwned;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use serde_json::Value;

/// How a front end spells an option.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Spelling {
    /// `--select-folds`, `--select-folds 1`.
    CommandLine,
    /// `select_folds`, `select_folds=1`.
    Python,
}

impl Spelling {
    /// The option `name` (`snake_case`) as this front end writes it: `--select-folds` or
    /// `select_folds` (`file`, the records given, is `FILE` or `x`).
    pub fn name(self, name: &str) -> String {
        // The records themselves: the command line's positional FILE arguments, Python's first
        // argument `x`.
        if name == "file" {
            return match self {
                Spelling::CommandLine => "FILE".to_owned(),
                Spelling::Python => "x".to_owned(),
            };
        }
        match self {
            Spelling::CommandLine => format!("--{}", name.replace('_', "-")),
            Spelling::Python => name.to_owned(),
        }
    }

    /// The option `name` set to `value`: `--dt 0` or `dt=0`; with an empty `value`, the option
    /// as a thing to set: `--dt` or `dt=`; a flag set, `True`: `--repair` or `repair=True`.
    pub fn setting(self, name: &str, value: &str) -> String {
        match self {
            // A flag is set by its name alone.
            Spelling::CommandLine if value.is_empty() || value == "True" => self.name(name),
            Spelling::CommandLine => format!("--{} {value}", name.replace('_', "-")),
            Spelling::Python => format!("{name}={value}"),
        }
    }

    /// `text` with every option it names spelled for this front end. Library messages name
    /// options between `«` and `»`: `«terms»` (the option), `«dt=»` (the option to set: `--dt`,
    /// `dt=`) and `«select_folds=1»` (set to a value: `--select-folds 1`, `select_folds=1`).
    pub fn render(self, text: &str) -> String {
        let mut out = String::with_capacity(text.len());
        let mut rest = text;
        while let Some(open) = rest.find('«') {
            let Some(close) = rest[open..].find('»') else {
                break;
            };
            out.push_str(&rest[..open]);
            let inner = &rest[open + '«'.len_utf8()..open + close];
            match inner.split_once('=') {
                Some((name, value)) => out.push_str(&self.setting(name, value)),
                None => out.push_str(&self.name(inner)),
            }
            rest = &rest[open + close + '»'.len_utf8()..];
        }
        out.push_str(rest);
        out
    }
}

/// A bad option, or a bad combination of options: which one (its `snake_case` name), the value
/// given if it is about one value, and why. Its text names options as [`Spelling::render`] reads
/// them; [`OptionError::spelled`] renders it for a front end.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "«{option}{}»{} {reason}",
    value.as_ref().map(|v| format!("={v}")).unwrap_or_default(),
    if *sentence { "" } else { ":" }
)]
pub struct OptionError {
    option: String,
    value: Option<String>,
    reason: String,
    /// The reason goes on from the option's name (`--bit-errors needs --counts`), no colon.
    sentence: bool,
}

impl OptionError {
    /// `option` is wrong as a whole (a combination, a missing partner): `reason` says why.
    pub fn new(option: impl Into<String>, reason: impl fmt::Display) -> Self {
        Self {
            option: option.into(),
            value: None,
            reason: reason.to_string(),
            sentence: false,
        }
    }

    /// `option` is wrong as a whole, said in a sentence whose subject is the option:
    /// `OptionError::sentence("bit_errors", "needs «counts»")` reads `--bit-errors needs
    /// --counts`.
    pub fn sentence(option: impl Into<String>, rest: impl fmt::Display) -> Self {
        Self {
            sentence: true,
            ..Self::new(option, rest)
        }
    }

    /// `option` cannot take `value`: `reason` says why.
    pub fn value(option: impl Into<String>, value: impl fmt::Display, reason: impl fmt::Display) -> Self {
        Self {
            option: option.into(),
            value: Some(value.to_string()),
            reason: reason.to_string(),
            sentence: false,
        }
    }

    /// `option` cannot take `value`, as the library's check `error` found: its reason alone
    /// (`must be between 2 and 1024`), the option's name and value being said already.
    pub fn checked(
        option: impl Into<String>,
        value: impl fmt::Display,
        error: &dyn std::error::Error,
    ) -> Self {
        Self::value(option, value, reason(error))
    }

    /// The option's name, `snake_case`.
    pub fn option(&self) -> &str {
        &self.option
    }

    /// Why it is refused.
    pub fn reason(&self) -> &str {
        &self.reason
    }

    /// The whole message as a front end shows it: `--select-folds 1: must be at least 2` or
    /// `select_folds=1: must be at least 2`; without a value `--terms: ...` or `terms: ...`.
    pub fn spelled(&self, spelling: Spelling) -> String {
        spelling.render(&self.to_string())
    }
}

/// The reason of a library's check of a parameter, without the name and value it repeats: the
/// `why` of `invalid NAME: VALUE (WHY)` and of `invalid NAME VALUE: WHY`, else the whole text.
fn reason(error: &dyn std::error::Error) -> String {
    let text = chain(error);
    if let Some(rest) = text.strip_prefix("invalid ") {
        if let (Some(open), true) = (rest.find(" ("), rest.ends_with(')'))
            && rest[..open]
                .split_once(": ")
                .is_some_and(|(_, value)| !value.contains(char::is_whitespace))
        {
            return rest[open + 2..rest.len() - 1].to_owned();
        }
        if let Some((_, why)) = rest.split_once(": ") {
            return why.to_owned();
        }
    }
    text
}

/// The text of an error and of every error behind it, joined by `: `.
pub(crate) fn chain(error: &dyn std::error::Error) -> String {
    let mut text = error.to_string();
    let mut source = error.source();
    while let Some(e) = source {
        let more = e.to_string();
        if !text.contains(&more) {
            text.push_str(": ");
            text.push_str(&more);
        }
        source = e.source();
    }
    text
}

/// Reads a request of type `T` (whose every field has a default, and which serialises every
/// field) from a JSON object of option names: unknown names are refused with the names they may
/// have meant, and a value that does not read is refused with its option's name.
pub fn from_object<T: Serialize + DeserializeOwned + Default>(value: Value) -> Result<T, OptionError> {
    let known = known_names::<T>();
    let Value::Object(map) = value else {
        return Err(OptionError::new("options", "expected an object of option names"));
    };
    for (name, v) in &map {
        if !known.iter().any(|k| k == name) {
            return Err(unknown_option(name, &known));
        }
        // Each option alone, so that an error names it.
        let single: Value = [(name.clone(), v.clone())]
            .into_iter()
            .collect::<serde_json::Map<_, _>>()
            .into();
        serde_json::from_value::<T>(single).map_err(|e| OptionError::value(name.as_str(), shown(v), e))?;
    }
    serde_json::from_value(Value::Object(map)).map_err(|e| OptionError::new("options", e))
}

/// A value as a Python user wrote it: texts in single quotes.
fn shown(value: &Value) -> String {
    match value {
        Value::String(s) => format!("'{s}'"),
        other => other.to_string(),
    }
}

/// The names of the options of `T`: the keys of its default, serialised.
pub fn known_names<T: Serialize + Default>() -> Vec<String> {
    match serde_json::to_value(T::default()) {
        Ok(Value::Object(map)) => map.keys().cloned().collect(),
        _ => Vec::new(),
    }
}

fn unknown_option(name: &str, known: &[String]) -> OptionError {
    let near: Vec<&str> = known
        .iter()
        .filter(|k| edit_distance(k, name) <= 2 || k.contains(name) || name.contains(k.as_str()))
        .map(String::as_str)
        .collect();
    let hint = if near.is_empty() {
        format!("unknown option; the options are {}", known.join(", "))
    } else {
        format!("unknown option; did you mean {}?", near.join(" or "))
    };
    OptionError::new(name, hint)
}

/// The Levenshtein distance of two short names.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut previous = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let substitution = previous + usize::from(ca != cb);
            previous = row[j + 1];
            row[j + 1] = substitution.min(row[j] + 1).min(row[j + 1] + 1);
        }
    }
    row[b.len()]
}

/// A value given as a number, a text or a list of texts, as its text: numbers as they print, a
/// list joined by `, ` (a list of terms), an object of such values as `key: value` parts
/// joined by `; ` (the terms of each equation by its coordinate).
fn as_text(value: Value) -> Result<String, String> {
    match value {
        Value::Object(map) => map
            .into_iter()
            .map(|(k, v)| as_text(v).map(|v| format!("{k}: {v}")))
            .collect::<Result<Vec<_>, _>>()
            .map(|parts| parts.join("; ")),
        Value::String(s) => Ok(s),
        Value::Number(n) => Ok(n.to_string()),
        Value::Bool(b) => Ok(b.to_string()),
        Value::Array(items) => items
            .into_iter()
            .map(|item| match item {
                Value::String(s) => Ok(s),
                other => Err(format!("expected a text, found {other}")),
            })
            .collect::<Result<Vec<_>, _>>()
            .map(|items| items.join(", ")),
        other => Err(format!("expected a text or a number, found {other}")),
    }
}

/// Serde of a value that reads from text ([`FromStr`]) and writes as text ([`fmt::Display`]): the
/// grammars of the options (`harmonic:1`, `auto:5..7`, `x', {1,cos(t)}*sin(x)`) are the types'
/// own, in their crates, and read the same from the command line and from Python.
pub(crate) mod text {
    use super::*;

    pub fn serialize<T: fmt::Display, S: Serializer>(value: &T, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(value)
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<T, D::Error>
    where
        T: FromStr,
        T::Err: fmt::Display,
        D: Deserializer<'de>,
    {
        let text = as_text(Value::deserialize(d)?).map_err(serde::de::Error::custom)?;
        text.parse().map_err(serde::de::Error::custom)
    }
}

/// [`text`] for an optional value: `null` is `None`.
pub(crate) mod optional_text {
    use super::*;

    pub fn serialize<T: fmt::Display, S: Serializer>(value: &Option<T>, s: S) -> Result<S::Ok, S::Error> {
        match value {
            Some(v) => s.collect_str(v),
            None => s.serialize_none(),
        }
    }

    pub fn deserialize<'de, T, D>(d: D) -> Result<Option<T>, D::Error>
    where
        T: FromStr,
        T::Err: fmt::Display,
        D: Deserializer<'de>,
    {
        match Value::deserialize(d)? {
            Value::Null => Ok(None),
            value => {
                let text = as_text(value).map_err(serde::de::Error::custom)?;
                text.parse().map(Some).map_err(serde::de::Error::custom)
            }
        }
    }
}
