//! SDO access rules of the core's object store on the PAM dictionary
//! (moved from the core when the PAM became a device).

use ecat_slave::al::AlState;
use ecat_slave::od::Od;
use ecat_slave::wire::coe::SdoAbortCode;

fn up(store: &Od, index: u16, sub: u8) -> Result<u64, SdoAbortCode> {
    let mut buf = [0u8; 8];
    let n = store.upload(index, sub, &mut buf)?;
    let mut raw = [0u8; 8];
    raw[..n].copy_from_slice(&buf[..n]);
    Ok(u64::from_le_bytes(raw))
}

#[test]
fn identity_reads_product_code() {
    let s = crate::store();
    assert_eq!(up(&s, 0x1018, 2), Ok(0x00C7_03F3));
}

#[test]
fn sdo_write_read_only_object_aborts_0601_0002() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0x1018, 1, &[1, 0, 0, 0], AlState::PreOp),
        Err(SdoAbortCode::ReadOnly)
    );
}

#[test]
fn current_above_range_aborts_0609_0031_and_below_0609_0032() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0x800D, 2, &5000u16.to_le_bytes(), AlState::PreOp),
        Err(SdoAbortCode::ValueTooHigh)
    );
    assert_eq!(
        s.download(0x800D, 2, &100u16.to_le_bytes(), AlState::PreOp),
        Err(SdoAbortCode::ValueTooLow)
    );
    assert_eq!(
        s.download(0x800D, 2, &2000u16.to_le_bytes(), AlState::Op),
        Ok(2000)
    );
    assert_eq!(up(&s, 0x800D, 2), Ok(2000));
}

#[test]
fn wrong_lengths_abort_0607_0012_and_0607_0013() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0x800D, 2, &[0, 0, 0, 0], AlState::PreOp),
        Err(SdoAbortCode::LengthTooHigh)
    );
    assert_eq!(
        s.download(0x800D, 2, &[7], AlState::PreOp),
        Err(SdoAbortCode::LengthTooLow)
    );
}

#[test]
fn unknown_object_and_subindex_abort() {
    let s = crate::store();
    assert_eq!(up(&s, 0x1234, 0), Err(SdoAbortCode::ObjectNotFound));
    assert_eq!(up(&s, 0x1018, 9), Err(SdoAbortCode::SubindexNotFound));
}

#[test]
fn write_only_password_cannot_be_read() {
    let s = crate::store();
    assert_eq!(up(&s, 0xF801, 1), Err(SdoAbortCode::WriteOnly));
}

#[test]
fn enum_value_outside_its_members_aborts_0609_0030() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0xF800, 2, &[7], AlState::PreOp),
        Err(SdoAbortCode::ValueRange)
    );
    assert_eq!(
        s.download(0xF800, 2, &[9], AlState::PreOp),
        Err(SdoAbortCode::ValueRange),
        "high bits set in a 3-bit enum"
    );
    assert_eq!(s.download(0xF800, 2, &[2], AlState::PreOp), Ok(2));
}

#[test]
fn pdo_assignment_is_writable_only_in_preop() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0x1C12, 1, &0x1600u16.to_le_bytes(), AlState::SafeOp),
        Err(SdoAbortCode::InvalidState)
    );
    assert!(
        s.download(0x1C12, 1, &0x1600u16.to_le_bytes(), AlState::PreOp)
            .is_ok()
    );
}

#[test]
fn device_name_uploads_as_string() {
    let s = crate::store();
    let mut buf = [0u8; 32];
    let n = s.upload(0x1008, 0, &mut buf).unwrap();
    assert_eq!(&buf[..n], b"PAM-199-P-ETC");
}

#[test]
fn negative_curve_point_round_trips() {
    let mut s = crate::store();
    assert_eq!(
        s.download(0x8006, 1, &(-5000i16).to_le_bytes(), AlState::PreOp),
        Ok(-5000)
    );
    assert_eq!(up(&s, 0x8006, 1), Ok((-5000i16) as u16 as u64));
}
