//! The ESI XML reader of the `esi` crate: `ecat_esi::xml::parse` (the
//! element tree over quick-xml), its accessors and ETG number notations
//! (`hex_dec`, `hex_binary`), and `ecat_esi::check::check`, which reads an
//! ESI back and compares it with an SII image (here the PAM's).
//!
//! Input: bytes; the first byte's low bit chooses strict UTF-8 (inputs
//! that are not UTF-8 are dropped) or lossy conversion of the rest.
//!
//! Invariants: no panic (also none from the tree accessors on every
//! element, attribute and text); `check` of the document against the PAM's
//! SII gives a result or an error, never a panic; the tree of a document
//! is the same when parsed twice (the reader is deterministic). The `esi`
//! crate has no writer for a parsed tree, so there is no parse -> emit ->
//! parse round trip here; the generator's output is a seed.
#![no_main]

use std::borrow::Cow;
use std::sync::OnceLock;

use ecat_esi::xml::{self, Element};
use libfuzzer_sys::fuzz_target;

fn pam_sii() -> &'static [u8] {
    static SII: OnceLock<Vec<u8>> = OnceLock::new();
    SII.get_or_init(|| ecat_esi::sii_image(&pam_199_p_etc::DEVICE))
}

/// Every accessor on every element (depth-limited by the tree itself).
fn walk(e: &Element, depth: usize) {
    if depth > 256 {
        return;
    }
    let _ = xml::hex_dec(&e.text);
    let _ = xml::hex_binary(&e.text);
    for (k, v) in &e.attrs {
        assert!(e.attr(k).is_some(), "attribute {k} not found again");
        let _ = xml::hex_dec(v);
        let _ = xml::hex_binary(v);
    }
    for c in &e.children {
        assert!(
            e.child(&c.name).is_some(),
            "child {} not found again",
            c.name
        );
        assert!(e.children_named(&c.name).count() >= 1);
        let _ = e.path(&c.name);
        let _ = e.text_at(&format!("{}/{}", c.name, c.name));
        walk(c, depth + 1);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&mode, rest)) = data.split_first() else {
        return;
    };
    let text: Cow<'_, str> = if mode & 1 == 0 {
        match std::str::from_utf8(rest) {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => return,
        }
    } else {
        String::from_utf8_lossy(rest)
    };
    let parsed = xml::parse(&text);
    if let Ok(root) = &parsed {
        walk(root, 0);
        let _ = root.path("Descriptions/Devices/Device/Type");
        let _ = root.text_at("Vendor/Id");
    }
    assert_eq!(parsed, xml::parse(&text), "the reader is not deterministic");
    if let Ok(mismatches) = ecat_esi::check::check(&text, pam_sii()) {
        for m in mismatches {
            let _ = m.to_string();
        }
    }
});
