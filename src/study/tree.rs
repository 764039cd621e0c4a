//! The grid file as a bare YAML tree with the place of every node, for two checks the
//! typed parse cannot make:
//!
//! - empty values refused ([`first_empty`]): a key written without a value
//!   (`clearance:`), or with `~` or `null`, would otherwise read as a key left out and
//!   silently take its default. No key of a grid file has "nothing" as a value;
//! - the dotted field of a place ([`field_at`]), in block and flow style alike
//!   (`grid.rpm[1]` in `grid: {rpm: [300, .nan]}`), for the typed parse's errors.

use std::fmt::{self, Write};

use serde::de::{self, Deserialize, Deserializer, MapAccess, SeqAccess, Visitor};
use serde_saphyr::Spanned;

/// A YAML node reduced to what the check needs: its children and whether it is empty.
enum Node {
    /// A mapping: its keys (as written, `None` for an empty key) and values.
    Map(Vec<(Spanned<Key>, Spanned<Node>)>),
    /// A sequence.
    Seq(Vec<Spanned<Node>>),
    /// No value: empty, `~` or `null`.
    Empty,
    /// A number, string or boolean.
    Scalar,
}

/// A mapping key as text; `None` when the key itself is empty.
struct Key(Option<String>);

/// Accepts any YAML node.
struct NodeVisitor;

impl<'de> Visitor<'de> for NodeVisitor {
    type Value = Node;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("any YAML value")
    }
    fn visit_unit<E>(self) -> Result<Node, E> {
        Ok(Node::Empty)
    }
    fn visit_none<E>(self) -> Result<Node, E> {
        Ok(Node::Empty)
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> Result<Node, D::Error> {
        Node::deserialize(d)
    }
    fn visit_bool<E>(self, _: bool) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_i64<E>(self, _: i64) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_u64<E>(self, _: u64) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_i128<E>(self, _: i128) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_u128<E>(self, _: u128) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_f64<E>(self, _: f64) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_str<E>(self, _: &str) -> Result<Node, E> {
        Ok(Node::Scalar)
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Node, A::Error> {
        let mut items = Vec::new();
        while let Some(item) = seq.next_element()? {
            items.push(item);
        }
        Ok(Node::Seq(items))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Node, A::Error> {
        let mut entries = Vec::new();
        while let Some(entry) = map.next_entry()? {
            entries.push(entry);
        }
        Ok(Node::Map(entries))
    }
}

impl<'de> Deserialize<'de> for Node {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(NodeVisitor)
    }
}

/// Accepts any scalar key as its text.
struct KeyVisitor;

impl Visitor<'_> for KeyVisitor {
    type Value = Key;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a key")
    }
    fn visit_unit<E>(self) -> Result<Key, E> {
        Ok(Key(None))
    }
    fn visit_none<E>(self) -> Result<Key, E> {
        Ok(Key(None))
    }
    fn visit_bool<E>(self, v: bool) -> Result<Key, E> {
        Ok(Key(Some(v.to_string())))
    }
    fn visit_i64<E>(self, v: i64) -> Result<Key, E> {
        Ok(Key(Some(v.to_string())))
    }
    fn visit_u64<E>(self, v: u64) -> Result<Key, E> {
        Ok(Key(Some(v.to_string())))
    }
    fn visit_f64<E>(self, v: f64) -> Result<Key, E> {
        Ok(Key(Some(v.to_string())))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Key, E> {
        Ok(Key(Some(v.to_string())))
    }
}

impl<'de> Deserialize<'de> for Key {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(KeyVisitor)
    }
}

/// The tree of `text`, or `None` when it does not parse. Every scalar is taken as it
/// is, `.nan` too: judging values is the typed parse's work.
fn parse(text: &str) -> Option<Spanned<Node>> {
    let mut options = serde_saphyr::Options::default();
    options.non_finite_float_policy = serde_saphyr::NonFiniteFloatPolicy::PassThrough;
    serde_saphyr::from_str_with_options(text, options).ok()
}

/// The first empty value or key of grid-file `text` in file order: its 1-based
/// (line, column), its dotted field (`bearing.clearance`, `grid.rpm[1]`) and the
/// message. `None` when there is none, or when the text does not parse (the grid
/// file's own parse reports that).
pub(super) fn first_empty(text: &str) -> Option<((u64, u64), String, String)> {
    let root = parse(text)?;
    if let Node::Empty = root.value {
        return Some((
            (1, 1),
            String::new(),
            "the grid file is empty: it needs `name`, `duration`, `sample_rate` and \
             `grid:`, `cases:` or a `design:`"
                .to_string(),
        ));
    }
    find(&root, &mut String::new())
}

/// The first empty value or key under `node`, whose field is `path`.
fn find(node: &Spanned<Node>, path: &mut String) -> Option<((u64, u64), String, String)> {
    let place = |s: &serde_saphyr::Location| (s.line(), s.column());
    match &node.value {
        Node::Scalar => None,
        Node::Empty => Some((
            place(&node.referenced),
            path.clone(),
            if path.ends_with(']') {
                "is empty (`~` or `null`); give a value or remove the item"
            } else {
                "has no value; give one, or leave the key out (an optional key then takes \
                 its default)"
            }
            .to_string(),
        )),
        Node::Seq(items) => items.iter().enumerate().find_map(|(k, item)| {
            let len = path.len();
            let _ = write!(path, "[{k}]");
            let found = find(item, path);
            path.truncate(len);
            found
        }),
        Node::Map(entries) => entries.iter().find_map(|(key, value)| {
            let Some(name) = &key.value.0 else {
                return Some((
                    place(&key.referenced),
                    path.clone(),
                    "a key is empty (`~` or `null`); name the key".to_string(),
                ));
            };
            let len = path.len();
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(name);
            let found = find(value, path);
            path.truncate(len);
            found
        }),
    }
}

/// The dotted field of the node or key at 1-based (`line`, `column`) of grid-file
/// `text` (`grid.rpm[1]`, `cases[0].location`), or `None` when no node starts there or
/// the text does not parse.
pub(super) fn field_at(text: &str, line: u64, column: u64) -> Option<String> {
    let root = parse(text)?;
    let at = |l: &serde_saphyr::Location| l.line() == line && l.column() == column;
    locate(&root, &mut String::new(), &at)
}

/// The path of the first node under `node` (whose field is `path`) that `at` picks:
/// the deepest one, as a node's children start where it does (a flow list and its
/// first item differ by the bracket).
fn locate(
    node: &Spanned<Node>,
    path: &mut String,
    at: &dyn Fn(&serde_saphyr::Location) -> bool,
) -> Option<String> {
    let here = at(&node.referenced).then(|| path.clone());
    let len = path.len();
    let deeper = match &node.value {
        Node::Scalar | Node::Empty => None,
        Node::Seq(items) => items.iter().enumerate().find_map(|(k, item)| {
            let _ = write!(path, "[{k}]");
            let found = locate(item, path, at);
            path.truncate(len);
            found
        }),
        Node::Map(entries) => entries.iter().find_map(|(key, value)| {
            if !path.is_empty() {
                path.push('.');
            }
            path.push_str(key.value.0.as_deref().unwrap_or("~"));
            let found = at(&key.referenced)
                .then(|| path.clone())
                .or_else(|| locate(value, path, at));
            path.truncate(len);
            found
        }),
    };
    deeper.or(here)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn empty_values_and_keys_are_found_with_their_place_and_field() {
        let found = |text: &str| first_empty(text).map(|(place, field, _)| (place, field));
        assert_eq!(found("name: a\nrpm: 300\ngrid: {b: [1, 2]}\n"), None);
        assert_eq!(
            found("name: a\nbearing:\n  clearance:\n  stiffness: 1\n"),
            Some(((3, 12), "bearing.clearance".into()))
        );
        assert_eq!(
            found("name: a\ngrid: {rpm: [300, ~]}\n"),
            Some(((2, 19), "grid.rpm[1]".into()))
        );
        assert_eq!(
            found("cases: [{rpm: null}]\n"),
            Some(((1, 15), "cases[0].rpm".into()))
        );
        assert_eq!(found("name: a\n~: 5\n").map(|f| f.1), Some(String::new()));
        // Quoted, they are strings: the grid file's own checks judge them.
        assert_eq!(found("name: '~'\nrpm: \"null\"\n"), None);
        assert_eq!(found("# nothing\n"), Some(((1, 1), String::new())));
        // Text that does not parse is left to the grid file's parse.
        assert_eq!(found("name: [a\n"), None);
    }

    #[test]
    fn fields_are_named_in_block_and_flow_style() {
        let text = "name: a\ngrid: {clearance: [.nan], rpm: [300, 600]}\ncases:\n  - rpm: x\n    location: y\n";
        assert_eq!(field_at(text, 1, 7).as_deref(), Some("name"));
        assert_eq!(field_at(text, 2, 20).as_deref(), Some("grid.clearance[0]"));
        assert_eq!(field_at(text, 2, 19).as_deref(), Some("grid.clearance"));
        assert_eq!(field_at(text, 2, 38).as_deref(), Some("grid.rpm[1]"));
        assert_eq!(field_at(text, 2, 7).as_deref(), Some("grid"));
        assert_eq!(field_at(text, 4, 10).as_deref(), Some("cases[0].rpm"));
        assert_eq!(field_at(text, 5, 5).as_deref(), Some("cases[0].location"));
        assert_eq!(field_at(text, 9, 1), None);
    }
}
