//! A tiny read-only XML element tree over quick-xml's reader (host tool).
//!
//! Used to read ESI and ENI files (the twin loader, `ecat-esi`'s `check`,
//! the tests). It keeps element names, attributes, the concatenated text,
//! the children in document order and the line each element starts on (for
//! messages that name the element and the line); comments, processing
//! instructions and namespaces are dropped. It writes nothing: generation
//! uses quick-xml's writer directly.

use quick_xml::Reader;
use quick_xml::events::{BytesStart, Event};

/// Deepest element nesting [`parse`] accepts (the root is level 1). Real
/// ESI and ENI files nest fewer than 20 levels; the limit keeps a hostile
/// file from building a tree deep enough to exhaust the stack in the
/// recursive code that walks it (clone, compare, the loaders).
pub const MAX_DEPTH: usize = 256;

/// An XML document could not be parsed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("XML error at line {line} (byte {position}): {message}")]
pub struct XmlError {
    /// Byte offset where the reader stopped.
    pub position: u64,
    /// Line (1-based) of that byte.
    pub line: u32,
    /// What went wrong.
    pub message: String,
}

/// One element with its attributes, text and child elements.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Element {
    /// Element name as written (prefix included).
    pub name: String,
    /// Attributes in document order, values unescaped.
    pub attrs: Vec<(String, String)>,
    /// Text content directly inside this element, unescaped and trimmed.
    pub text: String,
    /// Child elements in document order.
    pub children: Vec<Element>,
    /// Line (1-based) of the element's start tag (0 when built by hand).
    pub line: u32,
}

/// Drops the subtree iteratively: a tree built deep by code (the parser
/// stops at [`MAX_DEPTH`]) would overflow the stack in the recursive drop
/// the compiler generates.
impl Drop for Element {
    fn drop(&mut self) {
        let mut pending = std::mem::take(&mut self.children);
        while let Some(mut e) = pending.pop() {
            pending.append(&mut e.children);
        }
    }
}

impl Element {
    /// Value of attribute `name`.
    pub fn attr(&self, name: &str) -> Option<&str> {
        self.attrs
            .iter()
            .find(|(k, _)| k == name)
            .map(|(_, v)| v.as_str())
    }

    /// The first child named `name`.
    pub fn child(&self, name: &str) -> Option<&Element> {
        self.children.iter().find(|c| c.name == name)
    }

    /// All children named `name`.
    pub fn children_named<'a>(&'a self, name: &'a str) -> impl Iterator<Item = &'a Element> {
        self.children.iter().filter(move |c| c.name == name)
    }

    /// The element at the `/`-separated child path (first match per step).
    pub fn path(&self, path: &str) -> Option<&Element> {
        path.split('/')
            .filter(|s| !s.is_empty())
            .try_fold(self, |e, step| e.child(step))
    }

    /// Text of the element at `path` (see [`Self::path`]).
    pub fn text_at(&self, path: &str) -> Option<&str> {
        self.path(path).map(|e| e.text.as_str())
    }
}

/// Line numbers of byte offsets of one document. The reader asks in
/// document order, so the count continues from the last answer (linear in
/// the document, not quadratic); an earlier offset counts from the start.
struct Lines<'a> {
    text: &'a str,
    /// (byte offset, line at that offset) of the last answer.
    last: std::cell::Cell<(usize, u32)>,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        Lines {
            text,
            last: std::cell::Cell::new((0, 1)),
        }
    }

    /// The 1-based line of byte `position`.
    fn of(&self, position: u64) -> u32 {
        let end = usize::try_from(position)
            .unwrap_or(usize::MAX)
            .min(self.text.len());
        let (mut from, mut line) = self.last.get();
        if end < from {
            (from, line) = (0, 1);
        }
        let newlines = self
            .text
            .as_bytes()
            .get(from..end)
            .map_or(0, |b| b.iter().filter(|c| **c == b'\n').count());
        let line = line.saturating_add(u32::try_from(newlines).unwrap_or(u32::MAX));
        self.last.set((end, line));
        line
    }

    fn error(&self, position: u64, message: String) -> XmlError {
        XmlError {
            position,
            line: self.of(position),
            message,
        }
    }
}

fn start_element(
    start: &BytesStart<'_>,
    position: u64,
    lines: &Lines<'_>,
) -> Result<Element, XmlError> {
    let err = |message: String| lines.error(position, message);
    let name = String::from_utf8_lossy(start.name().as_ref()).into_owned();
    let mut attrs = Vec::new();
    for a in start.attributes() {
        let a = a.map_err(|e| err(e.to_string()))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a.unescape_value().map_err(|e| err(e.to_string()))?;
        attrs.push((key, value.into_owned()));
    }
    Ok(Element {
        name,
        attrs,
        text: String::new(),
        children: Vec::new(),
        line: lines.of(position),
    })
}

/// Parses `text` into its root element.
pub fn parse(text: &str) -> Result<Element, XmlError> {
    let mut reader = Reader::from_str(text);
    let lines = Lines::new(text);
    let mut stack: Vec<Element> = Vec::new();
    let mut root: Option<Element> = None;
    loop {
        let position = reader.buffer_position();
        let err = |message: String| lines.error(position, message);
        let event = reader.read_event().map_err(|e| err(e.to_string()))?;
        if matches!(event, Event::Start(_) | Event::Empty(_)) && stack.len() >= MAX_DEPTH {
            return Err(err(format!("XML nested deeper than {MAX_DEPTH} elements")));
        }
        match event {
            Event::Start(s) => stack.push(start_element(&s, position, &lines)?),
            Event::Empty(s) => {
                let e = start_element(&s, position, &lines)?;
                match stack.last_mut() {
                    Some(parent) => parent.children.push(e),
                    None if root.is_none() => root = Some(e),
                    None => return Err(err("second root element".into())),
                }
            }
            Event::End(_) => {
                let mut e = stack
                    .pop()
                    .ok_or_else(|| err("unbalanced end tag".into()))?;
                e.text = e.text.trim().to_string();
                match stack.last_mut() {
                    Some(parent) => parent.children.push(e),
                    None if root.is_none() => root = Some(e),
                    None => return Err(err("second root element".into())),
                }
            }
            Event::Text(t) => {
                if let Some(top) = stack.last_mut() {
                    let t = t.unescape().map_err(|e| err(e.to_string()))?;
                    top.text.push_str(&t);
                }
            }
            Event::CData(t) => {
                if let Some(top) = stack.last_mut() {
                    top.text.push_str(&String::from_utf8_lossy(&t));
                }
            }
            Event::Eof => break,
            _ => {}
        }
    }
    if !stack.is_empty() {
        let position = reader.buffer_position();
        return Err(lines.error(
            position,
            format!(
                "unclosed element <{}>",
                stack.last().map_or("", |e| &e.name)
            ),
        ));
    }
    root.ok_or_else(|| lines.error(0, "no root element".into()))
}

/// A number as ESI and ENI files write them: signed decimal, `#x` (ETG
/// `HexDecValue`) or `0x` hex.
pub fn number(text: &str) -> Option<i64> {
    let t = text.trim();
    match t
        .strip_prefix("#x")
        .or_else(|| t.strip_prefix("#X"))
        .or_else(|| t.strip_prefix("0x"))
        .or_else(|| t.strip_prefix("0X"))
    {
        Some(h) => i64::from_str_radix(h, 16).ok(),
        None => t.parse().ok(),
    }
}

/// Parses an ETG `HexDecValue`: `#x`-prefixed hex or signed decimal.
pub fn hex_dec(s: &str) -> Option<i64> {
    let s = s.trim();
    if let Some(h) = s.strip_prefix("#x").or_else(|| s.strip_prefix("#X")) {
        i64::from_str_radix(h, 16).ok()
    } else {
        s.parse().ok()
    }
}

/// Decodes `xs:hexBinary` text into bytes.
pub fn hex_binary(s: &str) -> Option<Vec<u8>> {
    let s = s.trim();
    if !s.len().is_multiple_of(2) {
        return None;
    }
    (0..s.len())
        .step_by(2)
        .map(|i| s.get(i..i + 2).and_then(|b| u8::from_str_radix(b, 16).ok()))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_nested_elements_attributes_and_escaped_text() {
        let doc =
            parse(r#"<?xml version="1.0"?><a x="1&amp;2"><b>t &lt; u</b><c/><b>second</b></a>"#)
                .unwrap();
        assert_eq!(doc.name, "a");
        assert_eq!(doc.attr("x"), Some("1&2"));
        assert_eq!(doc.text_at("b"), Some("t < u"));
        assert_eq!(doc.children_named("b").count(), 2);
        assert!(doc.child("c").is_some());
    }

    #[test]
    fn elements_and_errors_carry_their_line() {
        let doc = parse("<a>\n  <b/>\n  <c>\n    <d x=\"1\"/>\n  </c>\n</a>").unwrap();
        assert_eq!(doc.line, 1);
        assert_eq!(doc.child("b").unwrap().line, 2);
        assert_eq!(doc.path("c/d").unwrap().line, 4);
        let e = parse("<a>\n<b>\n</a>").unwrap_err();
        assert_eq!(e.line, 3, "{e}");
    }

    #[test]
    fn line_numbers_are_right_when_asked_out_of_order() {
        let l = Lines::new("a\nb\nc\nd");
        assert_eq!(l.of(6), 4);
        assert_eq!(l.of(2), 2, "an earlier offset counts again from the start");
        assert_eq!(l.of(4), 3);
        assert_eq!(l.of(99), 4, "beyond the end: the last line");
    }

    #[test]
    fn rejects_unbalanced_documents() {
        assert!(parse("<a><b></a>").is_err());
        assert!(parse("<a>").is_err());
        assert!(parse("").is_err());
    }

    /// `depth` nested `<a>` elements, one per line.
    fn nested(depth: usize) -> String {
        let mut doc = String::with_capacity(depth * 8);
        for _ in 0..depth {
            doc.push_str("<a>\n");
        }
        for _ in 0..depth {
            doc.push_str("</a>");
        }
        doc
    }

    #[test]
    fn a_document_nested_250000_deep_is_an_error_naming_the_line_not_a_crash() {
        let doc = nested(250_000);
        assert!(doc.len() > 1_000_000);
        let e = parse(&doc).unwrap_err();
        assert_eq!(e.line, MAX_DEPTH as u32 + 1, "{e}");
        assert_eq!(
            e.to_string(),
            format!(
                "XML error at line 257 (byte {}): XML nested deeper than 256 elements",
                4 * 256
            )
        );
        // Exactly the limit is fine.
        assert!(parse(&nested(MAX_DEPTH)).is_ok());
        assert!(parse(&format!("{}<b/>{}", "<a>".repeat(256), "</a>".repeat(256))).is_err());
    }

    #[test]
    fn a_tree_built_250000_deep_by_code_drops_without_overflowing_the_stack() {
        let mut e = Element::default();
        for _ in 0..250_000 {
            e = Element {
                name: "a".into(),
                attrs: Vec::new(),
                text: String::new(),
                children: vec![e],
                line: 0,
            };
        }
        drop(e);
    }

    #[test]
    fn hex_dec_and_hex_binary_decode_etg_notation() {
        assert_eq!(hex_dec("#x1A00"), Some(0x1A00));
        assert_eq!(hex_dec("-5"), Some(-5));
        assert_eq!(hex_dec("#xZZ"), None);
        assert_eq!(hex_binary("E803"), Some(vec![0xE8, 0x03]));
        assert_eq!(hex_binary("E80"), None);
    }
}
