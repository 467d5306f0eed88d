//! Replacing one field's value inside RON text, so `karstic tree set` can take the value
//! as the user writes it (`Sphere(center: (0, 0, 0), radius: 4)`, `NaN`, an absent
//! optional field) and let the tree-file parser judge it in place.
//!
//! The scanner knows only what delimits values: strings, raw strings, characters,
//! comments, brackets and commas.

/// Why a field cannot be spliced.
#[derive(Debug, PartialEq, Eq)]
pub enum SpliceError {
    /// A key on the way is not a field of the value it names (the fields found are
    /// listed); the last key of a path may be absent: it is added.
    NoField {
        /// The key.
        key: String,
        /// The fields there are.
        fields: Vec<String>,
    },
    /// The new value is not exactly one RON value.
    NotOneValue,
}

/// `text` (a RON value with named fields, e.g. `Primitive(name: "a", shape: …)`) with
/// the field at `path` (`["shape", "radius"]`) set to `value`. Struct and enum values
/// along the path are entered whatever their variant name (`shape` → `Sphere(…)`).
pub fn set_field(text: &str, path: &[&str], value: &str) -> Result<String, SpliceError> {
    let value = value.trim();
    if value.is_empty() || value_end(value, 0) != value.len() {
        return Err(SpliceError::NotOneValue);
    }
    let mut at = skip_attributes(text);
    for (depth, key) in path.iter().enumerate() {
        let last = depth + 1 == path.len();
        let Some(body) = fields(text, at) else {
            return Err(SpliceError::NoField {
                key: key.to_string(),
                fields: Vec::new(),
            });
        };
        match body.fields.iter().find(|f| f.key == *key) {
            Some(f) if last => {
                return Ok(format!(
                    "{}{value}{}",
                    &text[..f.value.0],
                    &text[f.value.1..]
                ));
            }
            Some(f) => at = f.value.0,
            None if last => {
                let open = body.open + 1;
                return Ok(format!(
                    "{}{key}: {value}, {}",
                    &text[..open],
                    &text[open..]
                ));
            }
            None => {
                return Err(SpliceError::NoField {
                    key: key.to_string(),
                    fields: body.fields.iter().map(|f| f.key.to_string()).collect(),
                });
            }
        }
    }
    Err(SpliceError::NoField {
        key: String::new(),
        fields: Vec::new(),
    })
}

/// The byte range, in a whole tree file's `text`, of the node whose `name` field is
/// `name`: the value that holds `name: "NAME"` among its named fields, searched through
/// named fields, lists and tuples in the order they are written. `None` when no value
/// holds it (or the text is not laid out as values the scanner knows).
pub fn find_named(text: &str, name: &str) -> Option<(usize, usize)> {
    let quoted = format!("{name:?}");
    let start = skip_attributes(text);
    search_named(text, start, value_end(text, start), &quoted)
}

/// [`find_named`] inside the value that spans `start..end`.
fn search_named(text: &str, start: usize, end: usize, quoted: &str) -> Option<(usize, usize)> {
    let i = skip_blank(text, start);
    if let Some(body) = fields(text, i) {
        let named = |f: &Field| f.key == "name" && &text[f.value.0..f.value.1] == quoted;
        if body.fields.iter().any(named) {
            return Some((i, trim_end(text, i, end)));
        }
        return body
            .fields
            .iter()
            .find_map(|f| search_named(text, f.value.0, f.value.1, quoted));
    }
    // A list, a tuple, or a variant of unnamed values (`Some(…)`): each element.
    let open = skip_blank(text, ident_end(text, i));
    if !matches!(text.as_bytes().get(open), Some(b'[' | b'(')) || open >= end {
        return None;
    }
    let mut j = open + 1;
    loop {
        j = skip_blank(text, j);
        if j >= end || matches!(text.as_bytes()[j], b']' | b')') {
            return None;
        }
        let e = value_end(text, j);
        if let Some(found) = search_named(text, j, e, quoted) {
            return Some(found);
        }
        j = skip_blank(text, e);
        if text.as_bytes().get(j) == Some(&b',') {
            j += 1;
        }
    }
}

/// `text` without the list element spanning `start..end` (a node [`find_named`] found)
/// and the comma after it; when the element stands on lines of its own, those lines go
/// with it.
pub fn remove_element(text: &str, (start, end): (usize, usize)) -> String {
    let b = text.as_bytes();
    let mut e = end;
    while e < b.len() && (b[e] == b' ' || b[e] == b'\t') {
        e += 1;
    }
    if b.get(e) == Some(&b',') {
        e += 1;
    }
    let line_start = text[..start].rfind('\n').map_or(0, |i| i + 1);
    let rest_end = text[e..].find('\n').map_or(text.len(), |i| e + i + 1);
    if text[line_start..start].trim().is_empty() && text[e..rest_end].trim().is_empty() {
        format!("{}{}", &text[..line_start], &text[rest_end..])
    } else {
        format!("{}{}", &text[..start], &text[e..])
    }
}

/// `text` with `element` appended to the list in field `key` of the value spanning
/// `start..end` (a node [`find_named`] found), indented as the list's last element is;
/// `None` when the value has no such list.
pub fn append_element(
    text: &str,
    (start, _end): (usize, usize),
    key: &str,
    element: &str,
) -> Option<String> {
    let body = fields(text, start)?;
    let list = body.fields.iter().find(|f| f.key == key)?;
    let (open, close) = (list.value.0, list.value.1.checked_sub(1)?);
    if text.as_bytes().get(open) != Some(&b'[') || text.as_bytes().get(close) != Some(&b']') {
        return None;
    }
    // The last element's end, and the indentation of its line.
    let mut j = open + 1;
    let mut last = None;
    loop {
        j = skip_blank(text, j);
        if j >= close {
            break;
        }
        let e = value_end(text, j);
        last = Some((j, trim_end(text, j, e)));
        j = skip_blank(text, e);
        if text.as_bytes().get(j) == Some(&b',') {
            j += 1;
        }
    }
    Some(match last {
        Some((first, end)) => {
            let line_start = text[..first].rfind('\n').map_or(0, |i| i + 1);
            let indent = &text[line_start..first];
            let sep = if indent.trim().is_empty() {
                format!(",\n{indent}")
            } else {
                ", ".to_string()
            };
            format!("{}{sep}{element}{}", &text[..end], &text[end..])
        }
        None => format!("{}{element}{}", &text[..open + 1], &text[open + 1..]),
    })
}

/// The value at the start of `text` (after its attributes) as a variant name and named
/// fields: `Sphere(center: (0, 0, 0), radius: 2)` → `("Sphere", [("center", "(0, 0, 0)"),
/// ("radius", "2")])`; `None` when it is not a list of named fields. What the editor's
/// inspector walks to lay out a node's parameters.
pub fn named_fields(text: &str) -> Option<(&str, Vec<(&str, &str)>)> {
    let start = skip_attributes(text);
    let body = fields(text, start)?;
    let name = text[start..ident_end(text, start)].trim();
    Some((
        name,
        body.fields
            .iter()
            .map(|f| (f.key, &text[f.value.0..f.value.1]))
            .collect(),
    ))
}

/// The elements of the list `[a, b, …]` that `text` is (white space around it allowed), as
/// written; `None` when it is not a list. What the editor's inspector shows as rows.
pub fn list_items(text: &str) -> Option<Vec<&str>> {
    let b = text.as_bytes();
    let mut i = skip_blank(text, 0);
    if b.get(i) != Some(&b'[') {
        return None;
    }
    let mut items = Vec::new();
    i += 1;
    loop {
        i = skip_blank(text, i);
        match b.get(i) {
            Some(b']') => return text[i + 1..].trim().is_empty().then_some(items),
            None => return None,
            _ => {}
        }
        let end = value_end(text, i);
        items.push(&text[i..trim_end(text, i, end)]);
        i = skip_blank(text, end);
        if b.get(i) == Some(&b',') {
            i += 1;
        }
    }
}

/// One `key: value` entry; `value` is its byte range.
struct Field<'t> {
    key: &'t str,
    value: (usize, usize),
}

/// The named fields of the value at `at`: an optional name, then `(key: value, …)`.
struct Body<'t> {
    open: usize,
    fields: Vec<Field<'t>>,
}

/// The fields of the value starting at (or after white space from) `at`, or `None` when
/// it is not a parenthesised list of named fields.
fn fields(text: &str, at: usize) -> Option<Body<'_>> {
    let b = text.as_bytes();
    let mut i = skip_blank(text, at);
    i = ident_end(text, i);
    i = skip_blank(text, i);
    if b.get(i) != Some(&b'(') {
        return None;
    }
    let open = i;
    let mut fields = Vec::new();
    i += 1;
    loop {
        i = skip_blank(text, i);
        if b.get(i) == Some(&b')') || i >= b.len() {
            return Some(Body { open, fields });
        }
        let key_end = ident_end(text, i);
        let colon = skip_blank(text, key_end);
        if key_end == i || b.get(colon) != Some(&b':') {
            return None;
        }
        let start = skip_blank(text, colon + 1);
        let end = value_end(text, start);
        fields.push(Field {
            key: &text[i..key_end],
            value: (start, trim_end(text, start, end)),
        });
        i = skip_blank(text, end);
        if b.get(i) == Some(&b',') {
            i += 1;
        }
    }
}

/// `text` without the `#![enable(…)]` attributes that open it: the value alone, as it
/// is written inside a tree file.
pub fn without_attributes(text: &str) -> &str {
    &text[skip_attributes(text)..]
}

/// The start of the value after the `#![enable(…)]` attributes that open a RON text.
fn skip_attributes(text: &str) -> usize {
    let mut i = skip_blank(text, 0);
    while text[i..].starts_with("#![") {
        i = text[i..]
            .find(']')
            .map_or(text.len(), |n| skip_blank(text, i + n + 1));
    }
    i
}

/// End of the identifier at `i` (`i` itself when there is none).
fn ident_end(text: &str, i: usize) -> usize {
    let b = text.as_bytes();
    let mut j = i;
    while j < b.len() && (b[j].is_ascii_alphanumeric() || b[j] == b'_') {
        j += 1;
    }
    j
}

/// `end` moved back over trailing white space, not before `start`.
fn trim_end(text: &str, start: usize, end: usize) -> usize {
    start + text[start..end].trim_end().len()
}

/// `i` moved past white space and comments.
fn skip_blank(text: &str, mut i: usize) -> usize {
    let b = text.as_bytes();
    loop {
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        if text[i..].starts_with("//") {
            i = text[i..].find('\n').map_or(b.len(), |n| i + n);
        } else if text[i..].starts_with("/*") {
            i = text[i + 2..].find("*/").map_or(b.len(), |n| i + 2 + n + 2);
        } else {
            return i;
        }
    }
}

/// End of the value starting at `i`: the first `,` or unmatched closing bracket outside
/// strings, characters, comments and nested brackets (or the end of the text).
fn value_end(text: &str, mut i: usize) -> usize {
    let b = text.as_bytes();
    let mut depth = 0usize;
    while i < b.len() {
        match b[i] {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                if depth == 0 {
                    return i;
                }
                depth -= 1;
            }
            b',' if depth == 0 => return i,
            b'"' => i = string_end(b, i + 1, false, 0),
            b'\'' => i = string_end_char(b, i + 1),
            b'r' if matches!(b.get(i + 1), Some(b'#' | b'"')) => {
                let hashes = b[i + 1..].iter().take_while(|&&c| c == b'#').count();
                i = string_end(b, i + 2 + hashes, true, hashes);
            }
            b'/' if matches!(b.get(i + 1), Some(b'/' | b'*')) => {
                i = skip_blank(text, i);
                continue;
            }
            _ => {}
        }
        i += 1;
    }
    b.len()
}

/// Index of the last byte closing a string whose contents start at `i`: its quote, then
/// `hashes` hashes for a raw string (which has no escapes).
fn string_end(b: &[u8], mut i: usize, raw: bool, hashes: usize) -> usize {
    while i < b.len() {
        match b[i] {
            b'\\' if !raw => i += 1,
            b'"' if b[i + 1..]
                .iter()
                .take(hashes)
                .filter(|&&c| c == b'#')
                .count()
                == hashes =>
            {
                return i + hashes;
            }
            _ => {}
        }
        i += 1;
    }
    b.len()
}

/// Index of the closing quote of a character literal whose contents start at `i`.
fn string_end_char(b: &[u8], mut i: usize) -> usize {
    while i < b.len() {
        match b[i] {
            b'\\' => i += 1,
            b'\'' => return i,
            _ => {}
        }
        i += 1;
    }
    b.len()
}

#[cfg(test)]
mod tests {
    #[test]
    fn list_items_are_the_top_level_elements() {
        assert_eq!(
            list_items(" [(0, 1), Abs(2, \"a,]\", 3), // one\n [4, 5],\n]"),
            Some(vec!["(0, 1)", "Abs(2, \"a,]\", 3)", "[4, 5]"])
        );
        assert_eq!(list_items("[]"), Some(vec![]));
        assert_eq!(list_items("(1, 2)"), None);
        assert_eq!(list_items("[1, 2] x"), None);
    }

    use super::*;

    #[test]
    fn find_named_finds_a_node_through_fields_lists_and_comments() {
        let text = "#![enable(implicit_some)]\n(version: 1, // name: \"b\" in a comment\n \
                    defs: [Primitive(name: \"a\", falloff: 1)],\n root: Blend(children: [\n \
                    Anchor(at: (0, 0), child: Primitive(name: \"b\", falloff: 2)),\n]))\n";
        let (s, e) = find_named(text, "b").unwrap();
        assert_eq!(&text[s..e], "Primitive(name: \"b\", falloff: 2)");
        let (s, e) = find_named(text, "a").unwrap();
        assert_eq!(&text[s..e], "Primitive(name: \"a\", falloff: 1)");
        assert_eq!(find_named(text, "c"), None);
    }

    #[test]
    fn elements_are_removed_with_their_lines_and_appended_at_the_lists_indent() {
        let text = "Blend(name: \"b\", children: [\n    A(name: \"x\"), // keep\n    \
                    A(name: \"y\"),\n])\n";
        let y = find_named(text, "y").unwrap();
        assert_eq!(
            remove_element(text, y),
            "Blend(name: \"b\", children: [\n    A(name: \"x\"), // keep\n])\n"
        );
        let b = find_named(text, "b").unwrap();
        let added = append_element(text, b, "children", "A(name: \"z\")").unwrap();
        assert!(
            added.contains("    A(name: \"y\"),\n    A(name: \"z\"),\n])"),
            "{added}"
        );
        assert_eq!(append_element(text, b, "carves", "A()"), None);
        let empty = "Blend(children: [])";
        assert_eq!(
            append_element(empty, (0, empty.len()), "children", "A()").unwrap(),
            "Blend(children: [A()])"
        );
    }

    const NODE: &str =
        r#"Primitive(name: "a, (b)", shape: Sphere(center: (0, 0, 0), radius: 2.0), falloff: 1.5)"#;

    #[test]
    fn sets_nested_absent_and_whole_fields() {
        assert_eq!(
            set_field(NODE, &["shape", "radius"], "4").unwrap(),
            r#"Primitive(name: "a, (b)", shape: Sphere(center: (0, 0, 0), radius: 4), falloff: 1.5)"#
        );
        assert_eq!(
            set_field(NODE, &["shape"], "Point(center: (1, 2, 3))").unwrap(),
            r#"Primitive(name: "a, (b)", shape: Point(center: (1, 2, 3)), falloff: 1.5)"#
        );
        assert_eq!(
            set_field(NODE, &["noise"], "(amplitude: 1)").unwrap(),
            r#"Primitive(noise: (amplitude: 1), name: "a, (b)", shape: Sphere(center: (0, 0, 0), radius: 2.0), falloff: 1.5)"#
        );
        assert_eq!(
            set_field(NODE, &["falloff"], " NaN ").unwrap(),
            r#"Primitive(name: "a, (b)", shape: Sphere(center: (0, 0, 0), radius: 2.0), falloff: NaN)"#
        );
    }

    #[test]
    fn lists_named_fields() {
        let (name, fields) = named_fields(NODE).unwrap();
        assert_eq!(name, "Primitive");
        assert_eq!(
            fields,
            [
                ("name", "\"a, (b)\""),
                ("shape", "Sphere(center: (0, 0, 0), radius: 2.0)"),
                ("falloff", "1.5")
            ]
        );
        assert_eq!(named_fields("(1, 2, 3)"), None);
        assert_eq!(named_fields("Bicubic"), None);
    }

    #[test]
    fn skips_the_attributes_of_serialized_text() {
        let text =
            "#![enable(implicit_some)]\n#![enable(unwrap_variant_newtypes)]\nA(\n    x: 1,\n)";
        assert_eq!(
            set_field(text, &["x"], "2").unwrap(),
            "#![enable(implicit_some)]\n#![enable(unwrap_variant_newtypes)]\nA(\n    x: 2,\n)"
        );
    }

    #[test]
    fn refuses_missing_paths_and_several_values() {
        assert_eq!(
            set_field(NODE, &["colour", "red"], "1"),
            Err(SpliceError::NoField {
                key: "colour".into(),
                fields: vec!["name".into(), "shape".into(), "falloff".into()],
            })
        );
        assert_eq!(
            set_field(NODE, &["falloff"], "1, energy: 3"),
            Err(SpliceError::NotOneValue)
        );
        assert_eq!(
            set_field(NODE, &["falloff"], ""),
            Err(SpliceError::NotOneValue)
        );
        assert!(set_field(NODE, &["falloff", "x"], "1").is_err());
    }

    #[test]
    fn strings_comments_and_raw_strings_do_not_end_values() {
        let text = "(a: r#\"x\"), (\"#, b: /* , */ 'c', d: \"\\\", \")";
        let body = fields(text, 0).unwrap();
        let keys: Vec<&str> = body.fields.iter().map(|f| f.key).collect();
        assert_eq!(keys, ["a", "b", "d"]);
        let d = &body.fields[2];
        assert_eq!(&text[d.value.0..d.value.1], "\"\\\", \"");
    }
}
