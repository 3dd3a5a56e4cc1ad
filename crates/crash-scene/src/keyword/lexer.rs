//! Reading a keyword deck into blocks: one keyword line and its data cards, with
//! comments (`$`) dropped, `*INCLUDE` files read in place (relative to the including
//! file, size-capped, cycles refused), trailing blank lines dropped, and the long
//! format (`*KEYWORD LONG=Y`, a `+` after a keyword; `-` back to standard) noted per
//! block. Nothing here knows what a keyword means: `deck` does.

use super::DeckError;
use crate::files;
use std::path::{Path, PathBuf};

/// Where a card is: index into `Lexed::files`, 1-based line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Loc {
    pub file: u32,
    pub line: usize,
}

/// One data line of a block.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Card {
    pub loc: Loc,
    pub text: String,
}

/// A keyword and its cards.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Block {
    /// Upper case, without the `*` and the format marker, e.g. `SECTION_SHELL_TITLE`.
    pub name: String,
    pub loc: Loc,
    /// Long format: fields of fewer than 20 characters are 20 wide.
    pub long: bool,
    pub cards: Vec<Card>,
}

/// A deck and every file it includes.
#[derive(Debug, Clone, Default)]
pub struct Lexed {
    /// Files as named for messages (the deck as given, includes joined to its
    /// directory).
    pub files: Vec<String>,
    pub blocks: Vec<Block>,
}

impl Lexed {
    pub fn file(&self, loc: Loc) -> &str {
        self.files.get(loc.file as usize).map_or("", String::as_str)
    }

    pub fn error(&self, loc: Loc, column: usize, keyword: &str, message: String) -> DeckError {
        DeckError {
            file: self.file(loc).to_string(),
            line: loc.line,
            column,
            keyword: keyword.to_string(),
            message,
        }
    }
}

/// Read the deck at `path` and its includes.
pub fn lex(path: &Path) -> Result<Lexed, DeckError> {
    let mut lx = Lexed::default();
    let mut state = State::default();
    let text = read(path, None, &lx)?;
    read_text(&mut lx, &mut state, path, text, &mut Vec::new())?;
    if let Some(b) = state.block.take() {
        lx.blocks.push(b);
    }
    for b in &mut lx.blocks {
        while b.cards.last().is_some_and(|c| c.text.trim().is_empty()) {
            b.cards.pop();
        }
    }
    Ok(lx)
}

#[derive(Debug, Default)]
struct State {
    block: Option<Block>,
    /// `*KEYWORD LONG=Y`: every keyword long unless marked `-`.
    long_default: bool,
    ended: bool,
}

/// A file's text, capped; `at` is the `*INCLUDE` card naming it (None for the deck).
fn read(path: &Path, at: Option<(Loc, usize)>, lx: &Lexed) -> Result<String, DeckError> {
    let bytes = files::read(path, files::MAX_FILE_BYTES).map_err(|p| {
        let message = p.describe(path, files::MAX_FILE_BYTES);
        match at {
            Some((loc, col)) => lx.error(loc, col, "INCLUDE", message),
            None => DeckError {
                file: path.display().to_string(),
                line: 0,
                column: 0,
                keyword: String::new(),
                message,
            },
        }
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let line = 1 + e.as_bytes()[..e.utf8_error().valid_up_to()]
            .iter()
            .filter(|&&b| b == b'\n')
            .count();
        DeckError {
            file: path.display().to_string(),
            line,
            column: 0,
            keyword: String::new(),
            message: "not UTF-8 text (keyword decks are text files)".into(),
        }
    })
}

fn read_text(
    lx: &mut Lexed,
    st: &mut State,
    path: &Path,
    text: String,
    stack: &mut Vec<PathBuf>,
) -> Result<(), DeckError> {
    let canonical = std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    let file = lx.files.len() as u32;
    lx.files.push(path.display().to_string());
    stack.push(canonical);
    let mut lines = text.lines().enumerate().peekable();
    while let Some((i, raw)) = lines.next() {
        if st.ended {
            break;
        }
        let loc = Loc { file, line: i + 1 };
        let line = raw.strip_suffix('\r').unwrap_or(raw);
        if line.starts_with('$') {
            continue;
        }
        if let Some(kw) = line.strip_prefix('*') {
            if let Some(b) = st.block.take() {
                lx.blocks.push(b);
            }
            let b = keyword_line(lx, st, loc, kw)?;
            match b.name.as_str() {
                "END" => st.ended = true,
                "INCLUDE" => {
                    // the file names follow as cards: read them now, in place
                    let mut names = Vec::new();
                    while let Some((j, next)) = lines.peek() {
                        let next = next.strip_suffix('\r').unwrap_or(next);
                        if next.starts_with('*') {
                            break;
                        }
                        let l = Loc { file, line: j + 1 };
                        lines.next();
                        if next.starts_with('$') || next.trim().is_empty() {
                            continue;
                        }
                        names.push((l, next.to_string()));
                    }
                    include(lx, st, path, loc, names, stack)?;
                }
                _ => st.block = Some(b),
            }
            continue;
        }
        match &mut st.block {
            Some(b) => b.cards.push(Card {
                loc,
                text: line.to_string(),
            }),
            None if line.trim().is_empty() => {}
            None => {
                return Err(lx.error(
                    loc,
                    1,
                    "",
                    "data before the first keyword (a deck starts with *KEYWORD)".into(),
                ))
            }
        }
    }
    stack.pop();
    Ok(())
}

/// `*NAME [+|-|%]` (and `*KEYWORD [memory] [LONG=Y|N]`).
fn keyword_line(lx: &Lexed, st: &mut State, loc: Loc, kw: &str) -> Result<Block, DeckError> {
    let end = kw
        .find(|c: char| c.is_whitespace() || c == '+' || c == '-' || c == '%')
        .unwrap_or(kw.len());
    let name = kw[..end].to_ascii_uppercase();
    let rest = kw[end..].trim();
    let mut long = st.long_default;
    if name == "KEYWORD" {
        for word in rest.split_whitespace() {
            match word.to_ascii_uppercase().as_str() {
                "LONG=Y" => st.long_default = true,
                "LONG=N" => st.long_default = false,
                "LONG=S" => return Err(lx.error(loc, 0, "KEYWORD", "LONG=S (long real fields, standard integer fields) is not supported: use LONG=Y or the standard format".into())),
                w if w.chars().all(|c| c.is_ascii_digit()) || w.ends_with('M') => {} // memory size
                w => return Err(lx.error(loc, 0, "KEYWORD", format!("`{w}` after *KEYWORD is not understood (supported: a memory size, LONG=Y, LONG=N)"))),
            }
        }
        long = st.long_default;
    } else {
        match rest {
            "" => {}
            "+" => long = true,
            "-" => long = false,
            "%" => return Err(lx.error(loc, 0, &name, "the I10 format (`%`) is not supported: use the standard, long (+) or free (comma) format".into())),
            r => return Err(lx.error(loc, 0, &name, format!("`{r}` after the keyword is not understood (a `+` marks the long format)"))),
        }
    }
    if name.is_empty() {
        return Err(lx.error(loc, 1, "", "a `*` line without a keyword name".into()));
    }
    Ok(Block {
        name,
        loc,
        long,
        cards: Vec::new(),
    })
}

/// `*INCLUDE`: each card names a file (a name ending in ` +` continues on the next
/// card), relative to the including file's directory.
fn include(
    lx: &mut Lexed,
    st: &mut State,
    from: &Path,
    kw: Loc,
    cards: Vec<(Loc, String)>,
    stack: &mut Vec<PathBuf>,
) -> Result<(), DeckError> {
    if cards.is_empty() {
        return Err(lx.error(kw, 0, "INCLUDE", "no file name follows".into()));
    }
    let mut names: Vec<(Loc, usize, String)> = Vec::new();
    let mut cont = false;
    for (loc, text) in cards {
        let t = text.trim_end();
        let col = text.len() - text.trim_start().len() + 1;
        let (part, more) = match t.strip_suffix(" +") {
            Some(p) => (p.trim(), true),
            None => (t.trim(), false),
        };
        match (cont, names.last_mut()) {
            (true, Some(last)) => last.2.push_str(part),
            _ => names.push((loc, col, part.to_string())),
        }
        cont = more;
    }
    let dir = from.parent().map(Path::to_path_buf).unwrap_or_default();
    for (loc, col, name) in names {
        let path = dir.join(&name);
        let canonical = std::fs::canonicalize(&path).unwrap_or_else(|_| path.clone());
        if stack.contains(&canonical) {
            return Err(lx.error(
                loc,
                col,
                "INCLUDE",
                format!(
                    "{} includes itself (through the files being read): a cycle",
                    path.display()
                ),
            ));
        }
        let text = read(&path, Some((loc, col)), lx)?;
        // an included file's keywords do not continue the block before *INCLUDE
        read_text(lx, st, &path, text, stack)?;
        if let Some(b) = st.block.take() {
            lx.blocks.push(b);
        }
        if st.ended {
            // *END in an include ends that file only
            st.ended = false;
        }
    }
    Ok(())
}
