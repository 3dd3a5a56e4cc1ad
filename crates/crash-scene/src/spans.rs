//! Where every key and value of a scene file sits: dotted key paths mapped to byte
//! spans, so that errors found after deserializing still point at the real line and
//! column.

use std::collections::BTreeMap;
use std::ops::Range;
use toml::de::{DeTable, DeValue};

/// Spans of one key: the key itself and its value (for array items both are the item).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    pub key: Range<usize>,
    pub value: Range<usize>,
}

/// Key path -> spans, for every key and array item of a document.
#[derive(Debug, Clone, Default)]
pub struct SpanIndex {
    entries: BTreeMap<String, Entry>,
}

impl SpanIndex {
    /// Index a document that is already known to parse (returns an empty index if not).
    pub fn new(text: &str) -> Self {
        let mut index = Self::default();
        if let Ok(doc) = DeTable::parse(text) {
            index.table("", doc.get_ref());
        }
        index
    }

    fn table(&mut self, prefix: &str, t: &DeTable<'_>) {
        for (k, v) in t.iter() {
            let path = if prefix.is_empty() {
                k.get_ref().to_string()
            } else {
                format!("{prefix}.{}", k.get_ref())
            };
            self.entries.insert(
                path.clone(),
                Entry {
                    key: k.span(),
                    value: v.span(),
                },
            );
            self.value(&path, v.get_ref());
        }
    }

    fn value(&mut self, path: &str, v: &DeValue<'_>) {
        match v {
            DeValue::Table(t) => self.table(path, t),
            DeValue::Array(a) => {
                for (i, item) in a.iter().enumerate() {
                    let p = format!("{path}[{i}]");
                    self.entries.insert(
                        p.clone(),
                        Entry {
                            key: item.span(),
                            value: item.span(),
                        },
                    );
                    self.value(&p, item.get_ref());
                }
            }
            _ => {}
        }
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    pub fn get(&self, path: &str) -> Option<&Entry> {
        self.entries.get(path)
    }

    /// Start offset for an error about `path`: its value if present, else the nearest
    /// enclosing table that exists (a missing key is reported where it belongs).
    pub fn offset(&self, path: &str) -> usize {
        let mut p = path;
        loop {
            if let Some(e) = self.entries.get(p) {
                return e.value.start;
            }
            match p.rfind(['.', '[']) {
                Some(i) => p = &p[..i],
                None => return 0,
            }
        }
    }

    /// Offset of the key itself (falls back to `offset`).
    pub fn key_offset(&self, path: &str) -> usize {
        self.entries
            .get(path)
            .map_or_else(|| self.offset(path), |e| e.key.start)
    }

    /// The table whose value span is exactly `span` (serde reports a missing field with
    /// the span of the table it belongs in). An array of tables and its item share the
    /// header's span: the item (the longer path, `bodies[1]`) wins.
    pub fn table_with_span(&self, span: &Range<usize>) -> Option<&str> {
        self.entries
            .iter()
            .filter(|(_, e)| e.value == *span)
            .map(|(p, _)| p.as_str())
            .max_by_key(|p| p.len())
    }

    /// The innermost key whose key span or value span holds `pos` (key spans win: an
    /// unknown-key error points at the key).
    pub fn path_at(&self, pos: usize) -> Option<&str> {
        let mut best: Option<(&str, usize)> = None;
        for (p, e) in &self.entries {
            for r in [&e.key, &e.value] {
                if r.start <= pos && pos < r.end.max(r.start + 1) {
                    let len = r.end - r.start;
                    if best.is_none_or(|(_, l)| len < l) {
                        best = Some((p.as_str(), len));
                    }
                }
            }
        }
        best.map(|(p, _)| p)
    }
}
