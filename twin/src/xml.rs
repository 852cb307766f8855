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

/// The text of an XML document as its bytes are written: a byte order
/// mark first (UTF-8, UTF-16LE/BE), else the encoding the XML declaration
/// names (`<?xml version="1.0" encoding="ISO-8859-1"?>`), else UTF-8 (XML
/// 1.0, 4.3.3 and appendix F). Labels are looked up as the WHATWG
/// Encoding Standard defines them (`encoding_rs`), so `ISO-8859-1`,
/// `ISO8859-1` and `latin1` decode as Windows-1252, which agrees with
/// ISO-8859-1 on every byte but 0x80..0x9F (C1 controls there, printable
/// characters in Windows-1252: no ESI means a control character).
/// Bytes that are not valid in the encoding are an error naming the line.
pub fn decode(bytes: &[u8]) -> Result<String, XmlError> {
    let (encoding, body) = match encoding_rs::Encoding::for_bom(bytes) {
        Some((enc, bom)) => (enc, bytes.get(bom..).unwrap_or(&[])),
        None => (declared_encoding(bytes)?, bytes),
    };
    match encoding.decode_without_bom_handling_and_without_replacement(body) {
        Some(text) => Ok(text.into_owned()),
        None => {
            // Where: the first byte the decoder refuses.
            let (text, _) = encoding.decode_without_bom_handling(body);
            let at = text.find('\u{FFFD}').unwrap_or(0);
            let prefix = text.get(..at).unwrap_or("");
            let line = 1 + prefix.matches('\n').count();
            Err(XmlError {
                position: prefix.len() as u64,
                line: u32::try_from(line).unwrap_or(u32::MAX),
                message: format!("bytes that are not {} text", encoding.name()),
            })
        }
    }
}

/// The encoding an XML declaration at the start of `bytes` names (UTF-8
/// without one). UTF-16 without a byte order mark shows as `<\0?\0` or
/// `\0<\0?`.
fn declared_encoding(bytes: &[u8]) -> Result<&'static encoding_rs::Encoding, XmlError> {
    match bytes.get(..4) {
        Some([b'<', 0, b'?', 0]) => return Ok(encoding_rs::UTF_16LE),
        Some([0, b'<', 0, b'?']) => return Ok(encoding_rs::UTF_16BE),
        _ => {}
    }
    let head = bytes.get(..bytes.len().min(256)).unwrap_or(bytes);
    let head = String::from_utf8_lossy(head);
    let Some(decl) = head
        .trim_start()
        .strip_prefix("<?xml")
        .and_then(|d| d.split("?>").next())
    else {
        return Ok(encoding_rs::UTF_8);
    };
    let Some(rest) = decl.split("encoding").nth(1) else {
        return Ok(encoding_rs::UTF_8);
    };
    let rest = rest
        .trim_start()
        .strip_prefix('=')
        .unwrap_or(rest)
        .trim_start();
    let quote = rest.chars().next().filter(|q| *q == '"' || *q == '\'');
    let label = match quote {
        Some(q) => rest.get(1..).and_then(|r| r.split(q).next()).unwrap_or(""),
        None => "",
    };
    encoding_rs::Encoding::for_label(label.trim().as_bytes())
        // A document that names UTF-16 but has no byte order mark was
        // caught above; a declaration read as ASCII is not UTF-16.
        .map(|e| {
            if e == encoding_rs::UTF_16LE || e == encoding_rs::UTF_16BE {
                encoding_rs::UTF_8
            } else {
                e
            }
        })
        .ok_or_else(|| XmlError {
            position: 0,
            line: 1,
            message: format!("unknown encoding '{label}' in the XML declaration"),
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

    /// `<a n="ä€"/>` with the declaration `decl`, encoded by `encode`.
    fn doc_in(decl: &str, encode: impl Fn(&str) -> Vec<u8>) -> Vec<u8> {
        encode(&format!("{decl}<a n=\"\u{e4}\"/>"))
    }

    #[test]
    fn documents_decode_by_their_bom_or_declaration() {
        let latin1 = |s: &str| s.chars().map(|c| c as u8).collect::<Vec<u8>>();
        let utf8 = |s: &str| s.as_bytes().to_vec();
        let utf16le = |s: &str| {
            s.encode_utf16()
                .flat_map(u16::to_le_bytes)
                .collect::<Vec<u8>>()
        };
        let utf16be = |s: &str| {
            s.encode_utf16()
                .flat_map(u16::to_be_bytes)
                .collect::<Vec<u8>>()
        };
        let cases: Vec<Vec<u8>> = vec![
            doc_in("<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>", latin1),
            doc_in("<?xml version='1.0' encoding='ISO8859-1'?>", latin1),
            doc_in("<?xml version=\"1.0\" encoding=\"windows-1252\"?>", latin1),
            doc_in("<?xml version=\"1.0\"?>", utf8),
            doc_in("", utf8),
            [
                b"\xEF\xBB\xBF".as_slice(),
                &doc_in("<?xml version=\"1.0\" encoding=\"utf-8\"?>", utf8),
            ]
            .concat(),
            [
                b"\xFF\xFE".as_slice(),
                &doc_in("<?xml version=\"1.0\" encoding=\"UTF-16\"?>", utf16le),
            ]
            .concat(),
            [
                b"\xFE\xFF".as_slice(),
                &doc_in("<?xml version=\"1.0\" encoding=\"UTF-16\"?>", utf16be),
            ]
            .concat(),
            doc_in("<?xml version=\"1.0\" encoding=\"UTF-16\"?>", utf16le),
        ];
        for bytes in cases {
            let text = decode(&bytes).unwrap();
            let doc = parse(&text).unwrap();
            assert_eq!(doc.attr("n"), Some("\u{e4}"), "{bytes:02x?}");
        }
    }

    #[test]
    fn bytes_that_are_not_the_declared_encoding_name_the_line() {
        let bad = b"<?xml version=\"1.0\"?>\n<a>\n<b n=\"\xE4\"/></a>";
        let e = decode(bad).unwrap_err();
        assert_eq!(e.line, 3, "{e}");
        assert!(e.message.contains("not UTF-8"), "{e}");
        let e = decode(b"<?xml version=\"1.0\" encoding=\"EBCDIC-42\"?><a/>").unwrap_err();
        assert!(e.message.contains("unknown encoding 'EBCDIC-42'"), "{e}");
        // Truncated and odd inputs are errors or text, never a panic.
        for b in [
            &b""[..],
            b"\xFF",
            b"\xFF\xFE<",
            b"<?xml encoding=",
            b"<?xml encoding=\"",
            b"\x00<\x00",
        ] {
            let _ = decode(b);
        }
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
