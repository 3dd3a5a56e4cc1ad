//! A parsed scene's text and spans, and the constructors of located errors.

use crate::error::{line_col, ErrorKind, SceneError};
use crate::spans::SpanIndex;
use std::collections::BTreeMap;

/// Where a key of a scene converted from a keyword deck was written in the deck.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Origin {
    pub file: String,
    /// 1-based line of the card.
    pub line: usize,
    /// The keyword and entity, e.g. `*SECTION_SHELL 2, T1`.
    pub what: String,
}

/// Key path (`bodies[0].thickness`) -> its origin; a key without an entry takes the
/// origin of the nearest enclosing key that has one.
pub type Origins = BTreeMap<String, Origin>;

/// The file a scene came from, with the spans of its keys.
#[derive(Debug, Clone)]
pub struct Ctx {
    pub file: String,
    pub text: String,
    pub spans: SpanIndex,
    /// Set for a scene converted from a keyword deck: errors then point at the deck's
    /// cards (file and line; no column), not at the generated TOML.
    pub origins: Option<Origins>,
}

/// Longest value text quoted in a message.
const QUOTE_MAX: usize = 60;

impl Ctx {
    pub fn new(file: &str, text: &str) -> Self {
        Self {
            file: file.into(),
            text: text.into(),
            spans: SpanIndex::new(text),
            origins: None,
        }
    }

    /// The deck card a key came from (see `Origins`).
    pub fn origin(&self, key: &str) -> Option<&Origin> {
        let origins = self.origins.as_ref()?;
        let mut p = key;
        loop {
            if let Some(o) = origins.get(p) {
                return Some(o);
            }
            p = &p[..p.rfind(['.', '['])?];
        }
    }

    fn at(&self, kind: ErrorKind, offset: usize, key: &str, message: String) -> SceneError {
        if self.origins.is_some() {
            let (file, line, message) = match self.origin(key) {
                Some(o) => (o.file.clone(), o.line, format!("{}: {message}", o.what)),
                None => (self.file.clone(), 0, message),
            };
            return SceneError {
                kind,
                file,
                line,
                column: 0,
                key: key.into(),
                message,
            };
        }
        let (line, column) = line_col(&self.text, offset);
        SceneError {
            kind,
            file: self.file.clone(),
            line,
            column,
            key: key.into(),
            message,
        }
    }

    /// The value of `key` as written (shortened), if the key is present.
    pub fn source(&self, key: &str) -> Option<String> {
        let e = self.spans.get(key)?;
        let s = self.text.get(e.value.clone())?;
        let one_line = s.split_whitespace().collect::<Vec<_>>().join(" ");
        Some(if one_line.chars().count() > QUOTE_MAX {
            format!(
                "{}...",
                one_line.chars().take(QUOTE_MAX).collect::<String>()
            )
        } else {
            one_line
        })
    }

    /// `key = <value as written>: what` at the value.
    pub fn value_error(
        &self,
        kind: ErrorKind,
        key: &str,
        what: impl std::fmt::Display,
    ) -> SceneError {
        let message = match self.source(key) {
            Some(v) => format!("{key} = {v}: {what}"),
            None => format!("{key}: {what}"),
        };
        self.at(kind, self.spans.offset(key), key, message)
    }

    pub fn invalid(&self, key: &str, what: impl std::fmt::Display) -> SceneError {
        self.value_error(ErrorKind::Invalid, key, what)
    }

    /// A required key is absent: located at the table it belongs in.
    pub fn missing(&self, key: &str, what: impl std::fmt::Display) -> SceneError {
        self.at(
            ErrorKind::Missing,
            self.spans.offset(key),
            key,
            format!("{key} is missing: {what}"),
        )
    }

    /// An error about a key as a whole (located at the key, not the value).
    pub fn key_error(
        &self,
        kind: ErrorKind,
        key: &str,
        what: impl std::fmt::Display,
    ) -> SceneError {
        self.at(
            kind,
            self.spans.key_offset(key),
            key,
            format!("{key}: {what}"),
        )
    }

    /// Turn a toml error (syntax or serde) into a located scene error.
    pub fn from_toml(&self, e: &toml::de::Error) -> SceneError {
        let offset = e.span().map_or(0, |s| s.start);
        let msg = e.message().trim().to_string();
        let path = self.spans.path_at(offset).map(str::to_string);
        if msg.starts_with("unknown field") {
            let key = path.unwrap_or_default();
            let (name, valid) = split_unknown(&msg);
            let mut text = format!("{key}: unknown key `{name}`; valid keys here: {valid}");
            if is_body_table(&key) {
                text.push_str(
                    " (a body's shape is one of the keys plate, sphere, cylinder, box, mesh)",
                );
            }
            return self.at(ErrorKind::UnknownKey, offset, &key, text);
        }
        if let Some(field) = msg
            .strip_prefix("missing field `")
            .and_then(|r| r.strip_suffix('`'))
        {
            // the span is the enclosing table's (empty at the top level): name the key by
            // that table's full path, array index included
            let table = e.span().and_then(|s| self.spans.table_with_span(&s));
            let key = match table {
                Some(p) => format!("{p}.{field}"),
                None => field.to_string(),
            };
            return self.at(
                ErrorKind::Missing,
                offset,
                &key,
                format!("{key} is missing: it is required here"),
            );
        }
        if msg.starts_with("invalid type") || msg.starts_with("invalid length") {
            let key = path.unwrap_or_default();
            let what = msg.replace("f64", "a number").replace("i64", "an integer");
            return self.value_error(ErrorKind::WrongType, &key, format!("wrong type: {what}"));
        }
        if path.is_some() && !self.spans.is_empty() {
            let key = path.unwrap_or_default();
            return self.value_error(ErrorKind::Invalid, &key, msg);
        }
        // syntax: name the key written on that line, if any
        let (line, _) = line_col(&self.text, offset);
        let key = self
            .text
            .lines()
            .nth(line - 1)
            .and_then(|l| l.split_once('='))
            .map(|(k, _)| k.trim().to_string())
            .unwrap_or_default();
        let text = if key.is_empty() {
            format!("invalid TOML: {msg}")
        } else {
            format!("{key}: invalid TOML: {msg}")
        };
        self.at(ErrorKind::Syntax, offset, &key, text)
    }
}

fn split_unknown(msg: &str) -> (String, String) {
    // "unknown field `foo`, expected one of `a`, `b`" / "..., expected `a`"
    let name = msg.split('`').nth(1).unwrap_or("").to_string();
    let valid = msg
        .split_once("expected")
        .map(|(_, v)| v.trim_start_matches(" one of").trim().replace('`', ""))
        .unwrap_or_default();
    (name, valid)
}

fn is_body_table(key: &str) -> bool {
    key.starts_with("bodies[") && key.matches('.').count() == 1
}
