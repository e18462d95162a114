//! A study's Markdown summary as HTML inside its section of the report: CommonMark with tables
//! and strikethrough (pulldown-cmark), headings moved down two levels (the page is h1, a study
//! h2), relative links and images re-rooted at the study folder, raw HTML shown as text.

use pulldown_cmark::{html, CowStr, Event, HeadingLevel, Options, Parser, Tag, TagEnd};

/// `markdown` rendered as HTML; relative URLs in it are taken relative to `base` (the study
/// folder as seen from index.html, e.g. "convergence/").
pub fn render(markdown: &str, base: &str) -> String {
    let options = Options::ENABLE_TABLES | Options::ENABLE_STRIKETHROUGH;
    let events = Parser::new_ext(markdown, options).map(|event| match event {
        Event::Start(Tag::Heading {
            level,
            id,
            classes,
            attrs,
        }) => Event::Start(Tag::Heading {
            level: demote(level),
            id,
            classes,
            attrs,
        }),
        Event::End(TagEnd::Heading(level)) => Event::End(TagEnd::Heading(demote(level))),
        Event::Start(Tag::Link {
            link_type,
            dest_url,
            title,
            id,
        }) => Event::Start(Tag::Link {
            link_type,
            dest_url: rebase(dest_url, base),
            title,
            id,
        }),
        Event::Start(Tag::Image {
            link_type,
            dest_url,
            title,
            id,
        }) => Event::Start(Tag::Image {
            link_type,
            dest_url: rebase(dest_url, base),
            title,
            id,
        }),
        // The summaries are ours, but the page must stay what the report made it.
        Event::Html(s) | Event::InlineHtml(s) => Event::Text(s),
        other => other,
    });
    let mut out = String::new();
    html::push_html(&mut out, events);
    out
}

fn demote(level: HeadingLevel) -> HeadingLevel {
    match level {
        HeadingLevel::H1 => HeadingLevel::H3,
        HeadingLevel::H2 => HeadingLevel::H4,
        HeadingLevel::H3 => HeadingLevel::H5,
        _ => HeadingLevel::H6,
    }
}

/// Whether `url` is relative to the document (no scheme, not absolute, not a fragment).
pub fn is_relative(url: &str) -> bool {
    let scheme = url.find(':').is_some_and(|i| {
        url[..i]
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    !(url.is_empty() || scheme || url.starts_with('/') || url.starts_with('#'))
}

fn rebase<'a>(url: CowStr<'a>, base: &str) -> CowStr<'a> {
    if is_relative(&url) {
        CowStr::from(format!("{base}{url}"))
    } else {
        url
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn headings_links_tables_code_and_raw_html() {
        let md = "# Convergence\n\nSlopes *near* −1.\n\n- pt\n- bdpt\n\n\
                  | a | b |\n|---|--:|\n| 1 | 2 |\n\n```\nlt study all\n```\n\n\
                  [csv](mse.csv) [web](https://example.org/x) [top](#t) ![f](mse.png)\n\n\
                  <script>alert(1)</script>\n";
        let html = render(md, "convergence/");
        for part in [
            "<h3>Convergence</h3>",
            "<em>near</em>",
            "<li>pt</li>",
            "<table>",
            "<td style=\"text-align: right\">2</td>",
            "<pre><code>lt study all\n</code></pre>",
            "href=\"convergence/mse.csv\"",
            "href=\"https://example.org/x\"",
            "href=\"#t\"",
            "src=\"convergence/mse.png\"",
            "&lt;script&gt;",
        ] {
            assert!(html.contains(part), "{part} not in {html}");
        }
        assert!(!html.contains("<script>"));
    }
}
