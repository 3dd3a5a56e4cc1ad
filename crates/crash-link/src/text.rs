//! Text that came from a peer (host names, error strings) made safe for a terminal or
//! a log: control characters (ANSI escape sequences, carriage returns, newlines,
//! backspaces), Unicode bidirectional overrides and other invisible format characters
//! are shown escaped, and the length is bounded.

/// Longest peer text shown [chars]; longer text is cut and marked.
pub const PEER_TEXT_MAX: usize = 256;

/// `s` with every control or format character escaped (`\u{1b}`) and at most
/// `PEER_TEXT_MAX` characters kept (then `...[N more chars]`).
pub fn escape_peer(s: &str) -> String {
    let mut out = String::with_capacity(s.len().min(PEER_TEXT_MAX * 2));
    let mut chars = s.chars();
    for c in chars.by_ref().take(PEER_TEXT_MAX) {
        if c == '\\' {
            out.push_str("\\\\");
        } else if c.is_control() || is_invisible_format(c) {
            out.extend(c.escape_unicode());
        } else {
            out.push(c);
        }
    }
    let rest = chars.count();
    if rest > 0 {
        out.push_str(&format!("...[{rest} more chars]"));
    }
    out
}

/// Bidi controls, zero-width characters and other format characters (Unicode Cf in
/// the ranges that matter for display spoofing).
fn is_invisible_format(c: char) -> bool {
    matches!(c,
        '\u{00ad}' | '\u{061c}' | '\u{180e}' | '\u{200b}'..='\u{200f}' | '\u{2028}'..='\u{202e}'
        | '\u{2060}'..='\u{206f}' | '\u{feff}' | '\u{fff9}'..='\u{fffb}')
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_length_bounded() {
        let e = escape_peer("evil\u{1b}[2J\rdone\n\u{202e}x");
        assert!(!e.chars().any(|c| c.is_control()), "{e}");
        assert!(e.contains("\\u{1b}[2J\\u{d}done\\u{a}\\u{202e}x"), "{e}");
        assert_eq!(escape_peer("host-1.lan"), "host-1.lan");
        let long = "a".repeat(10_000);
        let e = escape_peer(&long);
        assert!(
            e.len() < PEER_TEXT_MAX + 32 && e.ends_with("[9744 more chars]"),
            "{e}"
        );
    }
}
