//! A small scanner over RON text: where a field stands (for `file:line:column` messages)
//! and replacing a field's value (for `--set path=value` overrides).
//!
//! Paths are dotted field names and map keys with optional list indices:
//! `solver.tolerance`, `materials.soil.friction_angle`, `bodies[0].points_per_cell`.
//! The scanner understands comments, strings and bracket nesting; it does not validate.

use crate::error::SceneError;

/// 1-based (line, column) of byte offset `at`.
pub fn line_column(text: &str, at: usize) -> (usize, usize) {
    let before = &text[..at.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Where a RON parse error of `text` is, for scenes and study files alike: its line and
/// column (1-based) and the field it concerns, unless the message names it already. A
/// missing field is reported at the closing bracket of the struct that lacks it, so the
/// struct's own field names the place.
pub fn parse_error_place(text: &str, e: &ron::error::SpannedError) -> (usize, usize, Option<String>) {
    let message = e.code.to_string();
    let (line, column) = (e.span.start.line, e.span.start.col);
    let field = match e.code {
        ron::Error::MissingStructField { .. } => enclosing_field(text, line, column),
        _ => field_before(text, line, column),
    }
    .filter(|f| !message.contains(&format!("`{f}`")));
    (line, column, field)
}

/// The name of the field whose value holds 1-based (line, column): the nearest `name:`
/// before it, outside comments and strings.
pub fn field_before(text: &str, line: usize, column: usize) -> Option<String> {
    scan_to(text, offset(text, line, column)).last_field
}

/// The name of the field whose value is the struct, list or map that holds 1-based
/// (line, column), e.g. `solver` for a position inside `solver: ( .. )`; `None` at the top
/// level. A missing field is reported at its struct's closing bracket, where the nearest
/// name before would be the struct's last field rather than the struct.
pub fn enclosing_field(text: &str, line: usize, column: usize) -> Option<String> {
    let open = scan_to(text, offset(text, line, column)).open;
    // A list element or `Some(..)` is named by the field of the container around it.
    open.iter().rev().find_map(|&o| field_of_value(text, o))
}

/// Byte offset of 1-based (line, column), columns counted in characters.
pub fn offset(text: &str, line: usize, column: usize) -> usize {
    let start_of_line: usize = text
        .split_inclusive('\n')
        .take(line.saturating_sub(1))
        .map(str::len)
        .sum();
    text[start_of_line.min(text.len())..]
        .char_indices()
        .nth(column.saturating_sub(1))
        .map_or(text.len(), |(i, _)| start_of_line + i)
}

/// What the text before a byte offset leaves open.
struct Prefix {
    /// Offsets of the brackets still open, outermost first.
    open: Vec<usize>,
    /// The last `name:` or `"key":` at the depth reached (a closed container's own fields
    /// are forgotten: after `region: Polygon(vertices: ..)` it is `region`).
    last_field: Option<String>,
}

/// Reads the text up to byte offset `at`, skipping comments and string contents.
fn scan_to(text: &str, at: usize) -> Prefix {
    let b = text.as_bytes();
    let mut prefix = Prefix {
        open: Vec::new(),
        last_field: None,
    };
    // The identifier or string just read, as a candidate field name.
    let mut name: Option<&str> = None;
    // The last field of each open container's parent, to restore when it closes.
    let mut outer: Vec<Option<String>> = Vec::new();
    let mut i = skip_ws(text, 0);
    while i < at.min(b.len()) {
        let c = b[i];
        let next = if c == b'"' {
            let end = string_end(text, i);
            name = text.get(i + 1..end.saturating_sub(1).max(i + 1));
            end
        } else if c.is_ascii_alphanumeric() || c == b'_' {
            let end = ident_end(text, i);
            name = Some(&text[i..end]);
            end
        } else {
            match c {
                b'(' | b'[' | b'{' => {
                    prefix.open.push(i);
                    outer.push(prefix.last_field.clone());
                }
                b')' | b']' | b'}' => {
                    prefix.open.pop();
                    prefix.last_field = outer.pop().flatten();
                }
                b':' => prefix.last_field = name.map(str::to_string).or(prefix.last_field),
                _ => {}
            }
            name = None;
            i + text[i..].chars().next().map_or(1, char::len_utf8)
        };
        i = skip_ws(text, next);
    }
    prefix
}

/// The field whose value opens at byte offset `open`: `name: (`, `name: Variant(` or
/// `"key": Variant(`; `None` when no `name:` stands right before.
fn field_of_value(text: &str, open: usize) -> Option<String> {
    let head = text[..open].trim_end().trim_end_matches(is_ident_char).trim_end();
    let head = head.strip_suffix(':')?.trim_end();
    let name = match head.strip_suffix('"') {
        Some(quoted) => &quoted[quoted.rfind('"')? + 1..],
        None => &head[head.trim_end_matches(is_ident_char).len()..],
    };
    (!name.is_empty()).then(|| name.to_string())
}

/// Position of the field named by `path`: its name if present, else the deepest parent
/// found. `None` when not even the first segment is in the text.
pub fn field_position(text: &str, path: &str) -> Option<(usize, usize)> {
    let mut found = None;
    let mut open = top_open(text)?;
    for seg in segments(path).ok()? {
        match seg {
            Seg::Field(name) => match find_field(text, open, name) {
                Some((key, value)) => {
                    found = Some(key);
                    match descend(text, value) {
                        Some(o) => open = o,
                        None => break,
                    }
                }
                None => break,
            },
            Seg::Index(i) => match element(text, open, i) {
                Some(e) => {
                    found = Some(e);
                    match descend(text, e) {
                        Some(o) => open = o,
                        None => break,
                    }
                }
                None => break,
            },
        }
    }
    found.map(|at| line_column(text, at))
}

/// Applies one override `path=value`, replacing the value in the text (or inserting the
/// field into its parent when the scene relies on the default).
pub fn apply_override(text: &str, assignment: &str) -> Result<String, SceneError> {
    Ok(override_edit(text, assignment)?.0)
}

/// One `--set` applied to a scene's text: the bytes `at..at + new_len` of the new text
/// replaced `old_len` bytes of the text before it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Edit {
    /// Byte offset of the replacement in both texts.
    pub at: usize,
    /// Length of what was replaced (bytes).
    pub old_len: usize,
    /// Length of the replacement (bytes).
    pub new_len: usize,
    /// The `path=value` that made it.
    pub assignment: String,
}

impl Edit {
    /// The dotted path the override set.
    pub fn path(&self) -> &str {
        self.assignment.split('=').next().unwrap_or("").trim()
    }

    /// " (set by --set `path=value`)", for messages about the value it set.
    pub fn note(&self) -> String {
        format!(" (set by --set `{}`)", self.assignment)
    }
}

/// Where byte offset `at` of a text edited by `edits` (in the order applied) stood in the
/// text before them, and the edit whose replacement holds it, if one does: messages point
/// into the file the user wrote, not into the text the overrides made.
pub fn original_offset(edits: &[Edit], mut at: usize) -> (usize, Option<&Edit>) {
    let mut inside = None;
    for e in edits.iter().rev() {
        if at > e.at + e.new_len {
            at = at - e.new_len + e.old_len;
        } else if at >= e.at {
            // Inside a replacement or right after it (where a parser notices that the
            // value ended wrongly): the place of the value it replaced.
            at = e.at;
            inside = inside.or(Some(e));
        }
    }
    (at, inside)
}

/// Applies `path=value` to `text`; returns the new text and the edit made.
pub fn override_edit(text: &str, assignment: &str) -> Result<(String, Edit), SceneError> {
    let err = |m: &str| SceneError::Override(assignment.to_string(), m.to_string());
    let (path, value) = assignment
        .split_once('=')
        .ok_or_else(|| err("expected path=value"))?;
    let (path, value) = (path.trim(), value.trim());
    if path.is_empty() || value.is_empty() {
        return Err(err("expected path=value"));
    }
    let segs = segments(path).map_err(|m| err(&m))?;
    let edit = |at: usize, old_len: usize, new: String| {
        let e = Edit {
            at,
            old_len,
            new_len: new.len(),
            assignment: assignment.to_string(),
        };
        (format!("{}{}{}", &text[..at], new, &text[at + old_len..]), e)
    };
    let mut open = top_open(text).ok_or_else(|| err("the scene has no top-level struct"))?;
    for (k, seg) in segs.iter().enumerate() {
        let last = k + 1 == segs.len();
        match *seg {
            Seg::Field(name) => match find_field(text, open, name) {
                Some((_, v)) if last => {
                    let end = value_end(text, v);
                    return Ok(edit(v, end - v, value.to_string()));
                }
                Some((_, v)) => {
                    open = descend(text, v).ok_or_else(|| err(&format!("`{name}` holds no fields")))?
                }
                None if last => return Ok(edit(open + 1, 0, format!(" {name}: {value},"))),
                // A struct the file leaves to its defaults: written with the one field set
                // (`output.history_every=8` on a scene without `output`).
                None => {
                    let nested = nest(&segs[k..], value)
                        .ok_or_else(|| err(&format!("no field `{name}` in the scene")))?;
                    return Ok(edit(open + 1, 0, format!(" {nested},")));
                }
            },
            Seg::Index(i) => {
                let e = element(text, open, i).ok_or_else(|| err(&format!("no element [{i}]")))?;
                if last {
                    let end = value_end(text, e);
                    return Ok(edit(e, end - e, value.to_string()));
                }
                open = descend(text, e).ok_or_else(|| err(&format!("element [{i}] holds no fields")))?;
            }
        }
    }
    Err(err("empty path"))
}

/// `a: (b: (c: value))` for the fields `a.b.c`; `None` when a segment is an index.
fn nest(segs: &[Seg], value: &str) -> Option<String> {
    let (first, rest) = segs.split_first()?;
    let Seg::Field(name) = first else { return None };
    if rest.is_empty() {
        return Some(format!("{name}: {value}"));
    }
    Some(format!("{name}: ({})", nest(rest, value)?))
}

enum Seg<'a> {
    Field(&'a str),
    Index(usize),
}

/// The segments of a dotted path: `name`, `name[3]`, `name[0][1]`. Anything else (an
/// index that is not a whole number, text after a `]`, an empty name) is an error.
fn segments(path: &str) -> Result<Vec<Seg<'_>>, String> {
    let mut out = Vec::new();
    for part in path.split('.') {
        let (name, mut rest) = part.split_once('[').map_or((part, ""), |(n, r)| (n, r));
        if name.is_empty() || name.contains(']') {
            return Err(format!("`{part}` does not start with a field name"));
        }
        out.push(Seg::Field(name));
        while !rest.is_empty() {
            let (index, after) = rest
                .split_once(']')
                .ok_or_else(|| format!("`[{rest}` has no closing `]`"))?;
            let i = index
                .parse()
                .map_err(|_| format!("`[{index}]` is not an index (a whole number ≥ 0)"))?;
            out.push(Seg::Index(i));
            rest = match after.strip_prefix('[') {
                Some(r) => r,
                None if after.is_empty() => "",
                None => return Err(format!("`{after}` after `[{index}]` is not part of a path")),
            };
        }
    }
    Ok(out)
}

/// A character of a RON identifier (a field, variant or struct name).
fn is_ident_char(c: char) -> bool {
    c.is_alphanumeric() || c == '_'
}

/// End of the identifier starting at byte offset `at` (`at` itself when none starts there).
fn ident_end(text: &str, at: usize) -> usize {
    text[at..]
        .find(|c| !is_ident_char(c))
        .map_or(text.len(), |n| at + n)
}

/// Skips white space and comments from `at`.
fn skip_ws(text: &str, mut at: usize) -> usize {
    let b = text.as_bytes();
    loop {
        while at < b.len() && b[at].is_ascii_whitespace() {
            at += 1;
        }
        if text[at..].starts_with("//") {
            at = text[at..].find('\n').map_or(b.len(), |n| at + n);
        } else if text[at..].starts_with("/*") {
            at = text[at..].find("*/").map_or(b.len(), |n| at + n + 2);
        } else {
            return at;
        }
    }
}

/// End of a string literal starting at `at` (which holds the quote).
fn string_end(text: &str, at: usize) -> usize {
    let b = text.as_bytes();
    let mut i = at + 1;
    while i < b.len() {
        match b[i] {
            b'\\' => i += 2,
            b'"' => return i + 1,
            _ => i += 1,
        }
    }
    b.len()
}

/// Offset of the top-level struct's opening parenthesis.
fn top_open(text: &str) -> Option<usize> {
    let mut at = skip_ws(text, 0);
    while text[at..].starts_with("#!") {
        at = text[at..].find(']').map(|n| skip_ws(text, at + n + 1))?;
    }
    text[at..].find('(').map(|n| at + n)
}

/// Walks the items of the container opened at `open`, calling `f(token_start, depth)` at
/// each token boundary at depth 0; stops at the closing bracket or when `f` says so.
fn scan<T>(text: &str, open: usize, mut f: impl FnMut(usize, u8) -> Option<T>) -> Option<T> {
    let b = text.as_bytes();
    let mut at = open + 1;
    let mut depth = 0i32;
    loop {
        at = skip_ws(text, at);
        if at >= b.len() {
            return None;
        }
        let c = b[at];
        if depth == 0 {
            if let Some(t) = f(at, c) {
                return Some(t);
            }
        }
        match c {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' => {
                depth -= 1;
                if depth < 0 {
                    return None;
                }
            }
            b'"' => {
                at = string_end(text, at);
                continue;
            }
            _ => {}
        }
        at = next_char(text, at);
    }
}

/// Offset of the character after the one starting at `at`.
fn next_char(text: &str, at: usize) -> usize {
    at + text[at..].chars().next().map_or(1, char::len_utf8)
}

/// Finds `name: value` directly inside the container at `open`; returns the offsets of the
/// name and of the value.
fn find_field(text: &str, open: usize, name: &str) -> Option<(usize, usize)> {
    let b = text.as_bytes();
    let mut prev_boundary = true;
    scan(text, open, |at, c| {
        let boundary = prev_boundary;
        prev_boundary = matches!(c, b',' | b'(' | b'{' | b'[');
        if !boundary {
            return None;
        }
        let key_end = if c == b'"' {
            let end = string_end(text, at);
            // An unterminated string ends the text: compare what it holds.
            (text.get(at + 1..end.saturating_sub(1)) == Some(name)).then_some(end)
        } else {
            let end = ident_end(text, at);
            (&text[at..end] == name).then_some(end)
        }?;
        let colon = skip_ws(text, key_end);
        (b.get(colon) == Some(&b':')).then(|| (at, skip_ws(text, colon + 1)))
    })
}

/// Offset of element `index` of the list or tuple opened at `open`.
fn element(text: &str, open: usize, index: usize) -> Option<usize> {
    let mut count = 0usize;
    let mut expecting = true;
    scan(text, open, |at, c| {
        if c == b',' {
            count += 1;
            expecting = true;
            return None;
        }
        if matches!(c, b')' | b']' | b'}') {
            return None;
        }
        if expecting && count == index {
            return Some(at);
        }
        expecting = false;
        None
    })
}

/// The opening bracket of the fields of the value at `value`, looking through an enum
/// variant name and `Some(...)`.
fn descend(text: &str, value: usize) -> Option<usize> {
    let mut at = skip_ws(text, value);
    let b = text.as_bytes();
    loop {
        let name_end = ident_end(text, at);
        let next = skip_ws(text, name_end);
        let c = *b.get(next)?;
        if !matches!(c, b'(' | b'[' | b'{') {
            return None;
        }
        if &text[at..name_end] == "Some" {
            at = skip_ws(text, next + 1);
            continue;
        }
        return Some(next);
    }
}

/// End of the value starting at `value` (exclusive, trailing space trimmed).
fn value_end(text: &str, value: usize) -> usize {
    let b = text.as_bytes();
    let mut at = value;
    let mut depth = 0i32;
    while at < b.len() {
        match b[at] {
            b'(' | b'[' | b'{' => depth += 1,
            b')' | b']' | b'}' if depth == 0 => break,
            b')' | b']' | b'}' => depth -= 1,
            b',' if depth == 0 => break,
            b'"' => {
                at = string_end(text, at);
                continue;
            }
            b'/' if text[at..].starts_with("//") || text[at..].starts_with("/*") => {
                if depth == 0 {
                    break;
                }
                at = skip_ws(text, at);
                continue;
            }
            _ => {}
        }
        at = next_char(text, at);
    }
    value + text[value..at].trim_end().len()
}

#[cfg(test)]
mod tests {
    use super::*;

    const TEXT: &str = r#"#![enable(implicit_some)]
// a comment with solver: in it
Scene(
    dimension: 2,
    materials: {
        "soil": MohrCoulomb(density: 2000.0, friction_angle: 20.0),
    },
    bodies: [
        (material: "soil", points_per_cell: [2, 2]),
        (material: "rock", points_per_cell: [3, 3]),
    ],
    solver: (time_step: Courant(0.2), damping: Viscous(beta: 0.1)),
)
"#;

    #[test]
    fn finds_nested_fields_keys_and_list_elements() {
        assert_eq!(field_position(TEXT, "dimension"), Some((4, 5)));
        assert_eq!(
            field_position(TEXT, "materials.soil.friction_angle"),
            Some((6, 46))
        );
        assert_eq!(field_position(TEXT, "bodies[1].material"), Some((10, 10)));
        assert_eq!(field_position(TEXT, "solver.damping"), Some((12, 39)));
        // A missing leaf points at its parent.
        assert_eq!(field_position(TEXT, "solver.tolerance"), Some((12, 5)));
        assert_eq!(field_position(TEXT, "nothing"), None);
    }

    #[test]
    fn overrides_replace_values_and_insert_missing_fields() {
        let t = apply_override(TEXT, "solver.damping=Kinetic").unwrap();
        assert!(t.contains("damping: Kinetic)"), "{t}");
        let t = apply_override(TEXT, "solver.tolerance=1e-4").unwrap();
        assert!(t.contains("solver: ( tolerance: 1e-4,time_step"), "{t}");
        let t = apply_override(TEXT, "bodies[1].points_per_cell=[1, 1]").unwrap();
        assert!(t.contains("(material: \"rock\", points_per_cell: [1, 1])"), "{t}");
        let t = apply_override(TEXT, "materials.soil.friction_angle=35").unwrap();
        assert!(t.contains("friction_angle: 35)"), "{t}");
        assert!(apply_override(TEXT, "solver").is_err());
        // A struct the text leaves out is written with the one field (the scene's own
        // parse then refuses a name it does not know); a missing element cannot be.
        let t = apply_override(TEXT, "nope.field=1").unwrap();
        assert!(t.contains("nope: (field: 1),"), "{t}");
        assert!(apply_override(TEXT, "nope[0].field=1").is_err());
    }

    #[test]
    fn a_position_is_named_by_its_own_field_and_by_the_field_holding_its_struct() {
        // Line 12 ends `damping: Viscous(beta: 0.1)),`: column 65 is `Viscous`'s closing
        // parenthesis, column 66 `solver`'s.
        assert_eq!(field_before(TEXT, 12, 65).as_deref(), Some("beta"));
        assert_eq!(enclosing_field(TEXT, 12, 66).as_deref(), Some("solver"));
        assert_eq!(enclosing_field(TEXT, 12, 65).as_deref(), Some("damping"));
        // A map entry is named by its key, a list element by the list.
        assert_eq!(enclosing_field(TEXT, 6, 66).as_deref(), Some("soil"));
        assert_eq!(enclosing_field(TEXT, 9, 51).as_deref(), Some("bodies"));
        // The top-level struct has no field.
        assert_eq!(enclosing_field(TEXT, 13, 1), None);
        // A colon in a comment names nothing.
        let commented = "a: (\n  b: 1, // note: here\n  c: x y)";
        assert_eq!(field_before(commented, 3, 8).as_deref(), Some("c"));
        assert_eq!(field_before(commented, 3, 3).as_deref(), Some("b"));
        // After a nested value the field holding it is the nearest, not its inner fields.
        assert_eq!(field_before(TEXT, 12, 66).as_deref(), Some("damping"));
        assert_eq!(field_before(TEXT, 12, 67).as_deref(), Some("solver"));
        assert_eq!(field_before(TEXT, 6, 67).as_deref(), Some("soil"));
    }
}
