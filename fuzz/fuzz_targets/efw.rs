//! The `.efw` firmware package parser: the header view (`EfwHeader`), the
//! header `Repr` (`EfwHeaderRepr::parse`/`emit`, `check_device`, `pack`),
//! the incremental `EfwValidator` the FoE server feeds, and the download
//! into an image store and the bootloader's decision after it; also the
//! boot state record (`BootState::decode`/`encode`).
//!
//! Input: one byte choosing the chunk size the validator is fed with, then
//! the image.
//!
//! Invariants: no panic; a parsed header emits bytes that parse to the
//! same header (and, without extension bytes, to the same bytes); the
//! validator gives the same result whatever the chunking, accepts exactly
//! the images the one-shot checks accept (header, device, exact length,
//! payload CRC) and hands out exactly the payload; an accepted image
//! without extension re-packs to the same bytes, downloads into a store
//! and is what the bootloader tries next; a decoded boot state record
//! encodes to a record that decodes to the same state. With a public key
//! (the key of seed `[7; 32]`, which signed the `pam-signed*` seeds) the
//! validator accepts exactly the images it accepts without one that are
//! flagged signed and whose signature verifies over `signed_message`.
#![no_main]

use ecat_slave::firmware::{
    self, BootOutcome, BootState, DeviceIdentity, EFW_FLAG_SIGNED, EFW_HEADER_LEN, EFW_SIGNATURE,
    EfwError, EfwHeader, EfwHeaderRepr, EfwValidator, STATE_RECORD_LEN, ValidatedImage, crc32,
    signed_message,
};
use ecat_sim::chain::{IMAGE_SLOT_CAPACITY, provision_factory};
use ecat_sim::image_store::VecStore;
use libfuzzer_sys::fuzz_target;

const PAM: DeviceIdentity = DeviceIdentity {
    vendor_id: pam_199_p_etc::VENDOR_ID,
    product_code: pam_199_p_etc::PRODUCT_CODE,
    revision: pam_199_p_etc::REVISION,
};

/// The key that signed the `pam-signed*` seeds.
fn fuzz_key() -> ed25519_compact::PublicKey {
    ed25519_compact::KeyPair::from_seed(ed25519_compact::Seed::new([7; 32])).pk
}

/// Feeds `img` in chunks of `chunk` bytes (0: one chunk); the result and
/// the payload bytes handed out.
fn validate(img: &[u8], chunk: usize) -> (Result<ValidatedImage, EfwError>, Vec<u8>) {
    validate_with(EfwValidator::new(PAM, IMAGE_SLOT_CAPACITY), img, chunk)
}

fn validate_with(
    mut v: EfwValidator,
    img: &[u8],
    chunk: usize,
) -> (Result<ValidatedImage, EfwError>, Vec<u8>) {
    let mut payload = Vec::new();
    let chunks: Box<dyn Iterator<Item = &[u8]>> = if chunk == 0 {
        Box::new(std::iter::once(img))
    } else {
        Box::new(img.chunks(chunk))
    };
    for c in chunks {
        let before = v.payload_received();
        match v.feed(c) {
            Ok(p) => {
                assert_eq!(before, payload.len(), "payload offset");
                assert!(c.ends_with(p), "payload is the end of the chunk");
                payload.extend_from_slice(p);
                let _ = (v.received(), v.header(), v.expected_len());
            }
            Err(_) => break,
        }
    }
    (v.finish(), payload)
}

fn header_view(img: &[u8]) {
    let h = EfwHeader::new_unchecked(img);
    let _ = (h.magic_ok(), h.format_version(), h.header_len(), h.flags());
    let _ = (
        h.vendor_id(),
        h.product_code(),
        h.revision_min(),
        h.revision_max(),
    );
    let _ = (h.version().as_str().len(), h.payload_len(), h.payload_crc());
    let _ = (
        h.header_crc(),
        h.computed_header_crc(),
        h.payload(),
        h.check_len(),
    );
    let _ = EfwHeader::new_checked(img).is_ok();
}

fn boot_state(img: &[u8]) {
    let Some(rec) = img.get(..STATE_RECORD_LEN) else {
        return;
    };
    if let Some(s) = BootState::decode(rec) {
        let again = BootState::decode(&s.encode());
        assert_eq!(again, Some(s), "boot state decode -> encode -> decode");
    }
    if let Some(second) = img.get(STATE_RECORD_LEN..2 * STATE_RECORD_LEN) {
        let _ = BootState::read_bank([rec, second]);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&sel, img)) = data.split_first() else {
        return;
    };
    header_view(img);
    boot_state(img);

    let parsed = EfwHeaderRepr::parse(img);
    if let Ok(h) = &parsed {
        let mut out = vec![0u8; h.buffer_len()];
        let n = h.emit(&mut out).expect("a parsed header emits");
        assert_eq!(n, h.buffer_len());
        assert_eq!(
            EfwHeaderRepr::parse(&out).as_ref(),
            Ok(h),
            "header parse -> emit -> parse"
        );
        if n == EFW_HEADER_LEN {
            assert_eq!(
                out[..],
                img[..n],
                "header without extension emits the same bytes"
            );
        } else {
            assert_eq!(out[..52], img[..52], "fixed header fields");
        }
        let _ = (h.image_len(), h.payload_len(), h.image_info());
    }

    // The validator, whatever the chunking, agrees with the one-shot checks.
    let chunk = match sel {
        0 => 0,
        s => usize::from(s % 64) + 1 + usize::from(s / 64) * 300,
    };
    let (result, payload) = validate(img, chunk);
    let (whole, whole_payload) = validate(img, 0);
    assert_eq!(
        result, whole,
        "validator result depends on the chunking ({chunk})"
    );
    let expected_ok = parsed.as_ref().is_ok_and(|h| {
        h.check_device(&PAM, IMAGE_SLOT_CAPACITY).is_ok()
            && img.len() == h.image_len()
            && crc32(&img[h.buffer_len()..]) == h.payload_crc
    });
    assert_eq!(
        result.is_ok(),
        expected_ok,
        "validator {result:?} vs header {parsed:?}"
    );
    // With a key: only images signed with it, whatever the chunking.
    let key = fuzz_key();
    let keyed = EfwValidator::new(PAM, IMAGE_SLOT_CAPACITY).with_public_key(*key);
    let (keyed, _) = validate_with(keyed, img, chunk);
    let signature_ok = parsed.as_ref().is_ok_and(|h| h.flags & EFW_FLAG_SIGNED != 0)
        && signed_message(img).is_ok_and(|parts| {
            let sig = img.get(EFW_SIGNATURE).and_then(|s| <[u8; 64]>::try_from(s).ok());
            sig.is_some_and(|s| {
                key.verify(parts.concat(), &ed25519_compact::Signature::new(s))
                    .is_ok()
            })
        });
    assert_eq!(
        keyed.is_ok(),
        expected_ok && signature_ok,
        "keyed validator {keyed:?}"
    );
    let Ok(validated) = result else {
        return;
    };
    let h = parsed.expect("checked above");
    assert_eq!(validated.header, h);
    assert_eq!(payload, &img[h.buffer_len()..], "payload handed out");
    assert_eq!(payload, whole_payload);

    if h.buffer_len() == EFW_HEADER_LEN {
        let mut out = vec![0u8; img.len()];
        let n = firmware::pack(&h, &payload, &mut out).expect("pack");
        assert_eq!(out[..n], *img, "pack(header, payload) gives the image back");
    }

    // Download it as the FoE server does, then power on.
    let mut store = VecStore::new(IMAGE_SLOT_CAPACITY);
    provision_factory(&mut store).expect("factory image");
    let slot = firmware::begin_download(&mut store).expect("begin");
    let step = if chunk == 0 {
        payload.len().max(1)
    } else {
        chunk
    };
    for (i, c) in payload.chunks(step).enumerate() {
        firmware::write_chunk(&mut store, slot, i * step, c).expect("write");
    }
    let info = firmware::finish_download(&mut store, slot, &validated).expect("finish");
    assert_eq!(info, validated.info());
    firmware::commit_pending(&mut store).expect("commit");
    let decision = firmware::power_on(&mut store);
    assert_eq!(
        decision.outcome,
        BootOutcome::Trial { attempt: 1 },
        "{decision:?}"
    );
    assert_eq!(decision.version, h.version);
    assert_eq!(decision.slot, Some(slot));
});
