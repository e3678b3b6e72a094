//! A tiny Markdown → HTML renderer for the stages' `.md` reports: headings,
//! paragraphs, pipe tables, lists, fenced code, inline code, bold, italics and
//! links. Enough for what rig-lab writes; no new crate, and everything is
//! escaped first so a report can never inject markup.

/// HTML-escapes text for element content and attribute values.
pub fn escape(s: &str) -> String {
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

/// Renders Markdown to an HTML fragment. `heading_shift` demotes headings
/// (a report's `#` becomes `<h3>` with shift 2) so they nest under the page's sections.
pub fn to_html(md: &str, heading_shift: usize) -> String {
    let lines: Vec<&str> = md.lines().collect();
    let mut out = String::new();
    let mut para: Vec<&str> = Vec::new();
    let flush = |para: &mut Vec<&str>, out: &mut String| {
        if !para.is_empty() {
            out.push_str(&format!("<p>{}</p>\n", inline(&para.join(" "))));
            para.clear();
        }
    };
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i];
        let trimmed = line.trim();
        if trimmed.is_empty() {
            flush(&mut para, &mut out);
            i += 1;
        } else if let Some(fence) = trimmed.strip_prefix("```") {
            flush(&mut para, &mut out);
            let _lang = fence.trim();
            let mut code = Vec::new();
            i += 1;
            while i < lines.len() && !lines[i].trim_start().starts_with("```") {
                code.push(lines[i]);
                i += 1;
            }
            i += 1; // the closing fence (or the end of the text)
            out.push_str(&format!("<pre><code>{}</code></pre>\n", escape(&code.join("\n"))));
        } else if let Some((level, text)) = heading(trimmed) {
            flush(&mut para, &mut out);
            let h = (level + heading_shift).min(6);
            out.push_str(&format!("<h{h}>{}</h{h}>\n", inline(text)));
            i += 1;
        } else if is_table_row(trimmed) && i + 1 < lines.len() && is_separator(lines[i + 1].trim()) {
            flush(&mut para, &mut out);
            let header = cells(trimmed);
            let align: Vec<&str> = cells(lines[i + 1].trim())
                .iter()
                .map(|c| match (c.starts_with(':'), c.ends_with(':')) {
                    (true, true) => "center",
                    (false, true) => "right",
                    _ => "",
                })
                .collect();
            let style = |k: usize| match align.get(k) {
                Some(a) if !a.is_empty() => format!(" style=\"text-align:{a}\""),
                _ => String::new(),
            };
            out.push_str("<table>\n<thead><tr>");
            for (k, c) in header.iter().enumerate() {
                out.push_str(&format!("<th{}>{}</th>", style(k), inline(c)));
            }
            out.push_str("</tr></thead>\n<tbody>\n");
            i += 2;
            while i < lines.len() && is_table_row(lines[i].trim()) {
                out.push_str("<tr>");
                for (k, c) in cells(lines[i].trim()).iter().enumerate() {
                    out.push_str(&format!("<td{}>{}</td>", style(k), inline(c)));
                }
                out.push_str("</tr>\n");
                i += 1;
            }
            out.push_str("</tbody>\n</table>\n");
        } else if let Some(ordered) = list_item(trimmed).map(|(o, _)| o) {
            flush(&mut para, &mut out);
            let tag = if ordered { "ol" } else { "ul" };
            out.push_str(&format!("<{tag}>\n"));
            while i < lines.len() {
                let t = lines[i].trim();
                match list_item(t) {
                    Some((o, text)) if o == ordered => {
                        let mut item = text.to_string();
                        i += 1;
                        // Continuation lines: indented, not a new item.
                        while i < lines.len()
                            && lines[i].starts_with("  ")
                            && !lines[i].trim().is_empty()
                            && list_item(lines[i].trim()).is_none()
                        {
                            item.push(' ');
                            item.push_str(lines[i].trim());
                            i += 1;
                        }
                        out.push_str(&format!("<li>{}</li>\n", inline(&item)));
                    }
                    _ => break,
                }
            }
            out.push_str(&format!("</{tag}>\n"));
        } else {
            para.push(trimmed);
            i += 1;
        }
    }
    flush(&mut para, &mut out);
    out
}

fn heading(line: &str) -> Option<(usize, &str)> {
    let level = line.chars().take_while(|&c| c == '#').count();
    if (1..=6).contains(&level) && line[level..].starts_with(' ') { Some((level, line[level..].trim())) } else { None }
}

fn is_table_row(line: &str) -> bool {
    line.starts_with('|') && line.len() > 1
}

fn is_separator(line: &str) -> bool {
    is_table_row(line) && line.chars().all(|c| matches!(c, '|' | '-' | ':' | ' ')) && line.contains('-')
}

/// Cells of a pipe-table row; `\|` is a literal bar.
fn cells(line: &str) -> Vec<String> {
    let inner = line.trim().trim_start_matches('|');
    let inner = inner.strip_suffix('|').unwrap_or(inner);
    let mut cells = vec![String::new()];
    let mut chars = inner.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek() == Some(&'|') => {
                cells.last_mut().expect("non-empty").push('|');
                chars.next();
            }
            '|' => cells.push(String::new()),
            _ => cells.last_mut().expect("non-empty").push(c),
        }
    }
    cells.into_iter().map(|c| c.trim().to_string()).collect()
}

/// `- item`, `* item`, `1. item` → (ordered, text).
fn list_item(line: &str) -> Option<(bool, &str)> {
    if let Some(rest) = line.strip_prefix("- ").or_else(|| line.strip_prefix("* ")) {
        return Some((false, rest));
    }
    let digits = line.chars().take_while(char::is_ascii_digit).count();
    if digits > 0 && line[digits..].starts_with(". ") {
        return Some((true, &line[digits + 2..]));
    }
    None
}

/// Inline markup on already-split text: `code`, **bold**, *em* / _em_, [text](url).
fn inline(text: &str) -> String {
    let mut out = String::new();
    let chars: Vec<char> = text.chars().collect();
    let mut i = 0;
    let find = |from: usize, pat: &[char]| -> Option<usize> {
        (from..chars.len().saturating_sub(pat.len() - 1)).find(|&k| chars[k..k + pat.len()] == *pat)
    };
    let s = |a: usize, b: usize| chars[a..b].iter().collect::<String>();
    while i < chars.len() {
        let c = chars[i];
        if c == '`' {
            if let Some(end) = find(i + 1, &['`']) {
                out.push_str(&format!("<code>{}</code>", escape(&s(i + 1, end))));
                i = end + 1;
                continue;
            }
        } else if c == '*' && chars.get(i + 1) == Some(&'*') {
            if let Some(end) = find(i + 2, &['*', '*']).filter(|&e| e > i + 2) {
                out.push_str(&format!("<strong>{}</strong>", inline(&s(i + 2, end))));
                i = end + 2;
                continue;
            }
        } else if (c == '*' || c == '_') && chars.get(i + 1).is_some_and(|n| !n.is_whitespace()) {
            // `_` only opens emphasis at a word start, so snake_case names stay intact.
            let word_start = i == 0 || !chars[i - 1].is_alphanumeric();
            if (c == '*' || word_start)
                && let Some(end) = find(i + 1, &[c])
                    .filter(|&e| e > i + 1 && (c == '*' || chars.get(e + 1).is_none_or(|n| !n.is_alphanumeric())))
            {
                out.push_str(&format!("<em>{}</em>", inline(&s(i + 1, end))));
                i = end + 1;
                continue;
            }
        } else if c == '['
            && let Some(close) = find(i + 1, &[']', '('])
            && let Some(end) = find(close + 2, &[')'])
        {
            let url = s(close + 2, end);
            out.push_str(&format!("<a href=\"{}\">{}</a>", escape(&url), inline(&s(i + 1, close))));
            i = end + 1;
            continue;
        }
        out.push_str(&escape(&c.to_string()));
        i += 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_the_blocks_the_stages_write() {
        let md = "# Fit\n\nThe fit of **Table 4.5** uses `rig_model`\nwith 3 runs.\n\n| p | value |\n|---|--:|\n| J_1 | 0.0298 |\n| a \\| b | <x> |\n\n- one\n- two_three\n  continued\n\n1. first\n\n```\nlet x = 1 < 2;\n```\n";
        let html = to_html(md, 2);
        assert_eq!(
            html,
            "<h3>Fit</h3>\n\
             <p>The fit of <strong>Table 4.5</strong> uses <code>rig_model</code> with 3 runs.</p>\n\
             <table>\n<thead><tr><th>p</th><th style=\"text-align:right\">value</th></tr></thead>\n<tbody>\n\
             <tr><td>J_1</td><td style=\"text-align:right\">0.0298</td></tr>\n\
             <tr><td>a | b</td><td style=\"text-align:right\">&lt;x&gt;</td></tr>\n</tbody>\n</table>\n\
             <ul>\n<li>one</li>\n<li>two_three continued</li>\n</ul>\n\
             <ol>\n<li>first</li>\n</ol>\n\
             <pre><code>let x = 1 &lt; 2;</code></pre>\n"
        );
    }

    #[test]
    fn emphasis_links_and_escapes() {
        assert_eq!(inline("an *em* and _em_ in snake_case_name"), "an <em>em</em> and <em>em</em> in snake_case_name");
        assert_eq!(inline("[spec](a&b.md) <b>"), "<a href=\"a&amp;b.md\">spec</a> &lt;b&gt;");
        assert_eq!(inline("2 * 3 * 4"), "2 * 3 * 4");
        assert_eq!(inline("unclosed `tick"), "unclosed `tick");
    }
}
