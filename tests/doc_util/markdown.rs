//! The parts of a Markdown page the doc suites read: fenced code blocks (with their info
//! string and line) and picture links `![alt](path)`.

/// A fenced code block of a page.
#[derive(Debug)]
pub struct Fence {
    /// 1-based line of the opening fence.
    pub line: usize,
    /// The info string's first word (`sh`, `console`, `ron`, …); empty for a bare fence.
    pub lang: String,
    /// The info string's attributes after the language, split at commas (`no-run`).
    pub attrs: Vec<String>,
    /// The lines between the fences.
    pub body: Vec<String>,
}

impl Fence {
    /// Whether the info string carries `attr` (`sh,no-run`).
    pub fn has(&self, attr: &str) -> bool {
        self.attrs.iter().any(|a| a == attr)
    }
}

/// The fenced blocks of `text` (``` fences; an unclosed fence runs to the end).
pub fn fences(text: &str) -> Vec<Fence> {
    let mut out = Vec::new();
    let mut open: Option<Fence> = None;
    for (n, line) in text.lines().enumerate() {
        let trimmed = line.trim();
        match open.as_mut() {
            Some(_) if trimmed == "```" => out.extend(open.take()),
            Some(fence) => fence.body.push(line.to_string()),
            None => {
                // A backtick fence's info string holds no backtick (CommonMark): a line
                // opening with inline code is not a fence.
                if let Some(info) = trimmed.strip_prefix("```")
                    && !info.contains('`')
                {
                    let mut parts = info.split(',').map(|s| s.trim().to_string());
                    open = Some(Fence {
                        line: n + 1,
                        lang: parts.next().unwrap_or_default(),
                        attrs: parts.collect(),
                        body: Vec::new(),
                    });
                }
            }
        }
    }
    out.extend(open);
    out
}

/// The picture links `![alt](target)` of `text` outside code blocks: (1-based line, alt,
/// target).
pub fn picture_links(text: &str) -> Vec<(usize, String, String)> {
    // The lines of each block, its fences included.
    let code: Vec<(usize, usize)> = fences(text)
        .iter()
        .map(|f| (f.line, f.line + f.body.len() + 1))
        .collect();
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if code
            .iter()
            .any(|&(first, last)| (first..=last).contains(&(n + 1)))
        {
            continue;
        }
        let mut rest = line;
        while let Some(start) = rest.find("![") {
            let after = &rest[start + 2..];
            let Some(close) = after.find("](") else { break };
            let target_text = &after[close + 2..];
            let Some(end) = target_text.find(')') else {
                break;
            };
            out.push((
                n + 1,
                after[..close].to_string(),
                target_text[..end].to_string(),
            ));
            rest = &target_text[end..];
        }
    }
    out
}

#[test]
fn fences_and_links_are_read() {
    let text = "# t\n\n```sh,no-run\ncargo test\n```\n![a pic](img/a.png) and ![b](img/b.png)\n\
                ```\n![not](a link)\n```\n```` ```sh ```` is inline code, ![c](c.png)\n";
    let f = fences(text);
    assert_eq!(f.len(), 2);
    assert_eq!((f[0].line, f[0].lang.as_str()), (3, "sh"));
    assert!(f[0].has("no-run") && !f[1].has("no-run"));
    assert_eq!(f[0].body, ["cargo test"]);
    assert_eq!((f[1].line, f[1].lang.as_str()), (7, ""));
    let links = picture_links(text);
    assert_eq!(
        links,
        [
            (6, "a pic".to_string(), "img/a.png".to_string()),
            (6, "b".to_string(), "img/b.png".to_string()),
            (10, "c".to_string(), "c.png".to_string())
        ]
    );
}
