//! Comparing a command's output with the output a page shows, in the manner of trycmd and
//! snapbox: `[..]` in a line stands for any text within that line (a time, a size), and a
//! line holding only `...` for any number of lines (none included).

/// Whether `actual` is what `expected` shows. Runs of spaces count as one on both sides
/// (a column of figures right-aligned in a field of spaces may widen), and so do leading
/// and trailing spaces.
pub fn matches(expected: &str, actual: &str) -> bool {
    let squeeze = |text: &str| -> Vec<String> {
        text.lines()
            .map(|l| l.split_whitespace().collect::<Vec<_>>().join(" "))
            .collect()
    };
    let (exp, act) = (squeeze(expected), squeeze(actual));
    let exp: Vec<&str> = exp.iter().map(String::as_str).collect();
    let act: Vec<&str> = act.iter().map(String::as_str).collect();
    lines_match(&exp, &act)
}

fn lines_match(exp: &[&str], act: &[&str]) -> bool {
    match exp.split_first() {
        None => act.is_empty(),
        Some((&"...", rest)) => (0..=act.len()).any(|skip| lines_match(rest, &act[skip..])),
        Some((first, rest)) => act
            .split_first()
            .is_some_and(|(a, act_rest)| line_matches(first, a) && lines_match(rest, act_rest)),
    }
}

/// Whether `actual` is `expected` with each `[..]` replaced by some text.
fn line_matches(expected: &str, actual: &str) -> bool {
    let parts: Vec<&str> = expected.split("[..]").collect();
    let (first, last) = (parts[0], parts[parts.len() - 1]);
    if parts.len() == 1 {
        return expected == actual;
    }
    if !actual.starts_with(first) || actual.len() < first.len() + last.len() {
        return false;
    }
    let mut rest = &actual[first.len()..];
    for middle in &parts[1..parts.len() - 1] {
        match rest.find(middle) {
            Some(at) => rest = &rest[at + middle.len()..],
            None => return false,
        }
    }
    rest.ends_with(last)
}

#[test]
fn elisions_match_what_they_stand_for_and_nothing_else() {
    let shown = "region [..] at 2.5 m cells: [..] vertices\nwrote out/a.glb\n...\n  total [..] s";
    let run = "region [1, 2]..[3, 4] at 2.5 m cells: 17 vertices\nwrote out/a.glb\n  load 0.4 s\n  render 8 s\n  total 9.8 s\n";
    assert!(matches(shown, run));
    assert!(matches("a\n...\nb", "a\nb"));
    assert!(matches("[..]", "anything"));
    // A changed word, a missing line, an extra line, a wrong cell size: each fails.
    assert!(!matches(shown, &run.replace("wrote", "wrote:")));
    assert!(!matches(shown, &run.replace("  total 9.8 s\n", "")));
    assert!(!matches("a\nb", "a\nb\nc"));
    assert!(!matches(shown, &run.replace("2.5 m", "5 m")));
    assert!(!matches("x[..]xy", "xy"));
    // Aligned columns may widen.
    assert!(matches("  render       [..] s", "  render      59.62 s"));
}
