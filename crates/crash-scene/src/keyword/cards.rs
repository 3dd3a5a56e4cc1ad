//! A card split into its fields, by LS-DYNA's columns or by commas, and the fields read
//! as numbers the way LS-DYNA reads them.
//!
//! Fixed format: each keyword's cards have fields of given widths (mostly 10; *NODE
//! 8/16/16/16/8/8; *ELEMENT_SHELL 8 each; curve points 20/20); in the long format every
//! non-text field is at least 20 wide. A card holding a comma is in free format: its
//! fields are separated by commas and may be empty. Text beyond the last field, a tab
//! in a fixed card, or more comma fields than the card has are errors, never ignored.
//!
//! Numbers: a blank field is the field's default; reals accept `1.5e-3`, `1.5E-3`,
//! `1.5d-3` and Fortran's `1.5-3` (an exponent without its letter); integers are
//! digits with an optional sign.

use super::lexer::{Block, Card, Lexed, Loc};
use super::DeckError;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Int,
    Real,
    Text,
}

/// A field of a card layout: its name (as the LS-DYNA manual writes it), standard
/// width and kind.
#[derive(Debug, Clone, Copy)]
pub struct F {
    pub name: &'static str,
    pub width: usize,
    pub kind: Kind,
}

pub const fn i(name: &'static str, width: usize) -> F {
    F {
        name,
        width,
        kind: Kind::Int,
    }
}

pub const fn r(name: &'static str, width: usize) -> F {
    F {
        name,
        width,
        kind: Kind::Real,
    }
}

pub const fn t(name: &'static str, width: usize) -> F {
    F {
        name,
        width,
        kind: Kind::Text,
    }
}

/// A card's fields: trimmed text and 1-based column.
#[derive(Debug)]
pub struct Row<'a> {
    lx: &'a Lexed,
    pub keyword: &'a str,
    pub loc: Loc,
    layout: &'static [F],
    fields: Vec<(String, usize)>,
}

/// Split card `c` of block `b` by `layout`.
pub fn split<'a>(
    lx: &'a Lexed,
    b: &'a Block,
    c: &'a Card,
    layout: &'static [F],
) -> Result<Row<'a>, DeckError> {
    let text = c.text.as_str();
    let err = |col: usize, m: String| lx.error(c.loc, col, &b.name, m);
    let mut fields = Vec::with_capacity(layout.len());
    if layout.len() == 1 && layout[0].kind == Kind::Text {
        fields.push((text.trim().to_string(), 1));
    } else if text.contains(',') {
        let mut col = 1;
        for (k, f) in text.split(',').enumerate() {
            let lead = f.len() - f.trim_start().len();
            if k >= layout.len() {
                if !f.trim().is_empty() {
                    return Err(err(
                        col + lead,
                        format!(
                            "{} comma-separated fields, the card has {} ({})",
                            text.split(',').count(),
                            layout.len(),
                            names(layout)
                        ),
                    ));
                }
            } else {
                fields.push((f.trim().to_string(), col + lead));
            }
            col += f.chars().count() + 1;
        }
    } else {
        if let Some(p) = text.find('\t') {
            return Err(err(
                text[..p].chars().count() + 1,
                "a tab in a fixed-column card: its columns cannot be counted (use spaces, or commas between fields)".into(),
            ));
        }
        let chars: Vec<char> = text.chars().collect();
        let mut at = 0;
        for f in layout {
            let w = if b.long && f.kind != Kind::Text {
                f.width.max(20)
            } else {
                f.width
            };
            let end = (at + w).min(chars.len());
            let s: String = chars
                .get(at..end)
                .map_or(String::new(), |c| c.iter().collect());
            fields.push((s.trim().to_string(), at + 1));
            at += w;
        }
        if chars.len() > at {
            let extra: String = chars[at..].iter().collect();
            if !extra.trim().is_empty() {
                return Err(err(
                    at + 1 + (extra.len() - extra.trim_start().len()),
                    format!("text beyond the card's {} columns ({})", at, names(layout)),
                ));
            }
        }
    }
    while fields.len() < layout.len() {
        fields.push((String::new(), text.chars().count() + 1));
    }
    Ok(Row {
        lx,
        keyword: &b.name,
        loc: c.loc,
        layout,
        fields,
    })
}

fn names(layout: &[F]) -> String {
    layout.iter().map(|f| f.name).collect::<Vec<_>>().join(", ")
}

/// LS-DYNA's real syntax (see the module docs); finite values only.
pub fn parse_real(s: &str) -> Option<f64> {
    let mut t: String = s.replace(['d', 'D'], "e");
    if !t.contains(['e', 'E']) {
        // Fortran: 1.5-3 is 1.5e-3 (a sign after the first character)
        // after the first character, which may take several bytes (fuzzing found
        // a panic at `t[1..]` for a field starting with a non-ASCII character)
        let first = t.chars().next().map_or(0, char::len_utf8);
        if let Some(p) = t[first..].rfind(['+', '-']) {
            let p = p + first;
            t.insert(p, 'e');
        }
    }
    let ok = t
        .chars()
        .all(|c| c.is_ascii_digit() || matches!(c, '.' | '+' | '-' | 'e' | 'E'));
    if !ok {
        return None;
    }
    t.parse::<f64>().ok().filter(|v| v.is_finite())
}

impl Row<'_> {
    /// An error about field `k`, at its column.
    pub fn err(&self, k: usize, message: impl std::fmt::Display) -> DeckError {
        let (name, col) = (
            self.layout.get(k).map_or("?", |f| f.name),
            self.fields.get(k).map_or(0, |f| f.1),
        );
        self.lx
            .error(self.loc, col, self.keyword, format!("{name}: {message}"))
    }

    /// An error about the card as a whole.
    pub fn card_err(&self, message: impl std::fmt::Display) -> DeckError {
        self.lx
            .error(self.loc, 0, self.keyword, message.to_string())
    }

    pub fn raw(&self, k: usize) -> &str {
        self.fields.get(k).map_or("", |f| f.0.as_str())
    }

    pub fn text(&self, k: usize) -> &str {
        self.raw(k)
    }

    pub fn int(&self, k: usize) -> Result<Option<i64>, DeckError> {
        let s = self.raw(k);
        if s.is_empty() {
            return Ok(None);
        }
        s.parse::<i64>()
            .map(Some)
            .map_err(|_| self.err(k, format!("`{s}` is not an integer")))
    }

    pub fn int_or(&self, k: usize, default: i64) -> Result<i64, DeckError> {
        Ok(self.int(k)?.unwrap_or(default))
    }

    /// A required id (> 0).
    pub fn id(&self, k: usize) -> Result<i64, DeckError> {
        match self.int(k)? {
            Some(v) if v > 0 => Ok(v),
            Some(v) => Err(self.err(k, format!("{v}: an id must be > 0"))),
            None => Err(self.err(k, "missing: an id (> 0) is required")),
        }
    }

    pub fn real(&self, k: usize) -> Result<Option<f64>, DeckError> {
        let s = self.raw(k);
        if s.is_empty() {
            return Ok(None);
        }
        parse_real(s)
            .map(Some)
            .ok_or_else(|| self.err(k, format!("`{s}` is not a finite number")))
    }

    pub fn real_or(&self, k: usize, default: f64) -> Result<f64, DeckError> {
        Ok(self.real(k)?.unwrap_or(default))
    }

    /// A flag LS-DYNA reads as a real but means as an integer (`7.0` is 7).
    pub fn flag(&self, k: usize) -> Result<i64, DeckError> {
        let v = self.real_or(k, 0.0)?;
        if v.fract() != 0.0 || v.abs() > 1e9 {
            return Err(self.err(k, format!("{v}: must be a whole number")));
        }
        Ok(v as i64)
    }

    /// A field this reader does not support: it must be blank or zero.
    pub fn unsupported(&self, k: usize, what: &str) -> Result<(), DeckError> {
        let s = self.raw(k);
        if s.is_empty() || parse_real(s) == Some(0.0) {
            return Ok(());
        }
        Err(self.err(
            k,
            format!("{s}: {what} is not supported (leave it blank or 0)"),
        ))
    }

    /// Several unsupported fields (`k`, what) at once.
    pub fn unsupported_all(&self, list: &[(usize, &str)]) -> Result<(), DeckError> {
        list.iter().try_for_each(|(k, w)| self.unsupported(*k, w))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reals_in_every_spelling_lsdyna_accepts() {
        for (s, v) in [
            ("1.5e-3", 1.5e-3),
            ("1.5E+3", 1.5e3),
            ("1.5d-3", 1.5e-3),
            ("1.5D3", 1.5e3),
            ("1.5-3", 1.5e-3),
            ("-1.5-3", -1.5e-3),
            ("2.1+11", 2.1e11),
            ("-7", -7.0),
            (".5", 0.5),
            ("7.", 7.0),
        ] {
            assert_eq!(parse_real(s), Some(v), "{s}");
        }
        for s in ["inf", "nan", "1.0x", "1e400", "--1"] {
            assert_eq!(parse_real(s), None, "{s}");
        }
    }

    /// Regression (fuzz_inputs.rs, deck reader): a field starting with a multi-byte
    /// character panicked on a byte slice inside it; now it is simply not a real.
    #[test]
    fn a_real_field_starting_with_a_non_ascii_character_is_refused_not_a_panic() {
        for s in ["\u{e9}-3", "\u{fffd}1.5", "\u{1f600}", "\u{e9}"] {
            assert_eq!(parse_real(s), None, "{s}");
        }
    }
}
