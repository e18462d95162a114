//! Text made safe for the page: HTML escaping and relative URLs. A leaf both the page
//! (`html`) and the compact table (`overview`) use.

use std::fmt::Write;

/// Escapes text for HTML content and double-quoted attributes.
pub fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&#39;"),
            _ => out.push(c),
        }
    }
    out
}

/// `folder/rel` as a relative URL: every byte outside the unreserved set (and '/') escaped.
pub fn url(folder: &str, rel: &str) -> String {
    let mut out = String::new();
    for b in format!("{folder}/{rel}").bytes() {
        if b.is_ascii_alphanumeric() || b"-._~/".contains(&b) {
            out.push(b as char);
        } else {
            let _ = write!(out, "%{b:02X}");
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn escapes_and_urls() {
        assert_eq!(esc("a<b>&\"'"), "a&lt;b&gt;&amp;&quot;&#39;");
        assert_eq!(url("equal-time", "g/pt 1.png"), "equal-time/g/pt%201.png");
        assert_eq!(url("x", "ä\"#.svg"), "x/%C3%A4%22%23.svg");
    }
}
