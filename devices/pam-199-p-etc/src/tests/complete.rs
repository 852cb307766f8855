//! Complete access (core) on the PAM's records and arrays.

use ecat_slave::al::AlState;
use ecat_slave::od::Od;
use ecat_slave::od::complete::{check_download, upload};
use ecat_slave::wire::coe::SdoAbortCode;

/// [`check_download`] returning its `(subindex, value)` changes.
fn check(
    s: &Od,
    index: u16,
    sub: u8,
    data: &[u8],
    state: AlState,
) -> Result<Vec<(u8, i64)>, SdoAbortCode> {
    check_download(s, index, sub, data, state).map(|c| c.iter().collect())
}

#[test]
fn curve_object_uploads_42_points_after_a_padded_subindex_0() {
    let s = crate::store();
    let mut out = [0u8; 128];
    let n = upload(&s, 0x8006, 0, &mut out).unwrap();
    assert_eq!(n, 2 + 42 * 2);
    assert_eq!(out[0], 42);
    assert_eq!(out[1], 0, "padding byte");
    assert_eq!(i16::from_le_bytes([out[2], out[3]]), -10000);
    assert_eq!(i16::from_le_bytes([out[84], out[85]]), 10000);
    let n = upload(&s, 0x8006, 1, &mut out).unwrap();
    assert_eq!(n, 84);
}

#[test]
fn record_with_bit_fields_packs_gaps_as_zero_bits() {
    let mut s = crate::store();
    s.set(0x800A, 1, 1); // CCMODE ON (3 bits) + 5-bit gap
    s.set(0x800A, 3, 1); // MMTYPE LIN
    let mut out = [0u8; 64];
    let n = upload(&s, 0x800A, 1, &mut out).unwrap();
    // 3+5, 3+5, then TRIGGER, MIN:A, MAX:A, MIN:B, MAX:B (5 x 16 bits).
    assert_eq!(n, 2 + 10);
    assert_eq!(out[0], 0x01);
    assert_eq!(out[1], 0x01);
    assert_eq!(u16::from_le_bytes([out[2], out[3]]), 200);
}

#[test]
fn complete_download_of_the_curve_round_trips_and_is_all_or_nothing() {
    let mut s = crate::store();
    let mut img = [0u8; 86];
    img[0] = 42;
    for i in 0..42 {
        let v = (i as i16 - 21) * 100;
        img[2 + 2 * i..4 + 2 * i].copy_from_slice(&v.to_le_bytes());
    }
    let changes = check(&s, 0x8006, 0, &img, AlState::Op).unwrap();
    assert_eq!(changes.len(), 42);
    for (sub, v) in &changes {
        s.set(0x8006, *sub, *v);
    }
    assert_eq!(s.get(0x8006, 1), Some(-2100));
    // One point out of range: nothing is applied.
    img[2..4].copy_from_slice(&(-20000i16).to_le_bytes());
    assert_eq!(
        check(&s, 0x8006, 0, &img, AlState::Op),
        Err(SdoAbortCode::ValueTooLow)
    );
    // Wrong length.
    assert_eq!(
        check(&s, 0x8006, 0, &img[..85], AlState::Op),
        Err(SdoAbortCode::LengthTooLow)
    );
    let mut long = [0u8; 90];
    long[..86].copy_from_slice(&img);
    long[2..4].copy_from_slice(&0i16.to_le_bytes());
    assert_eq!(
        check(&s, 0x8006, 0, &long, AlState::Op),
        Err(SdoAbortCode::LengthTooHigh)
    );
}

#[test]
fn pdo_assignment_array_is_written_whole_only_in_preop() {
    let s = crate::store();
    let img = [2u8, 0, 0x00, 0x1A, 0x02, 0x1A];
    let c = check(&s, 0x1C13, 0, &img, AlState::PreOp).unwrap();
    assert_eq!(c.len(), 3);
    assert_eq!(
        check(&s, 0x1C13, 0, &img, AlState::SafeOp),
        Err(SdoAbortCode::InvalidState)
    );
    let too_many = [3u8, 0, 0, 0x1A, 2, 0x1A, 3, 0x1A];
    assert_eq!(
        check(&s, 0x1C13, 0, &too_many, AlState::PreOp),
        Err(SdoAbortCode::ValueTooHigh)
    );
}

#[test]
fn read_only_members_must_keep_their_value() {
    let s = crate::store();
    let mut out = [0u8; 32];
    let n = upload(&s, 0x1018, 0, &mut out).unwrap();
    assert_eq!(n, 2 + 16);
    assert_eq!(
        check(&s, 0x1018, 0, &out[..n], AlState::PreOp).map(|c| c.len()),
        Ok(0)
    );
    out[2] ^= 1;
    assert_eq!(
        check(&s, 0x1018, 0, &out[..n], AlState::PreOp),
        Err(SdoAbortCode::ReadOnly)
    );
}

#[test]
fn variables_and_write_only_members_refuse_complete_access() {
    let s = crate::store();
    let mut out = [0u8; 32];
    assert_eq!(
        upload(&s, 0x1000, 0, &mut out),
        Err(SdoAbortCode::CompleteAccessNotSupported)
    );
    assert_eq!(
        upload(&s, 0xF801, 0, &mut out),
        Err(SdoAbortCode::WriteOnly)
    );
    assert_eq!(
        upload(&s, 0x1234, 0, &mut out),
        Err(SdoAbortCode::ObjectNotFound)
    );
    assert_eq!(
        upload(&s, 0x8006, 5, &mut out),
        Err(SdoAbortCode::CompleteAccessNotSupported)
    );
}
