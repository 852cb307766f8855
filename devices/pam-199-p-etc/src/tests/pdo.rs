//! The core's PDO engine on the PAM's PDOs.

use ecat_slave::al::AlState;
use ecat_slave::pdo::{Direction, PdoError, ProcessImage, read_bits, write_bits};

#[test]
fn default_directional_images_are_5_and_14_bytes() {
    let s = crate::store();
    let out = <ProcessImage>::build(&s, Direction::Outputs, &crate::DEVICE.process_data).unwrap();
    let inp = <ProcessImage>::build(&s, Direction::Inputs, &crate::DEVICE.process_data).unwrap();
    assert_eq!(out.byte_len(), 5);
    assert_eq!(inp.byte_len(), 14);
    assert_eq!(out.sets(), 0b01, "the directional set only");
}

#[test]
fn outputs_unpack_into_enable_and_command_value() {
    let mut s = crate::store();
    let out = <ProcessImage>::build(&s, Direction::Outputs, &crate::DEVICE.process_data).unwrap();
    let cmd: i32 = -5000;
    let mut data = [0u8; 5];
    data[0] = 1;
    data[1..5].copy_from_slice(&cmd.to_le_bytes());
    out.unpack(&mut s, &data);
    assert_eq!(s.get(0x7000, 1), Some(1));
    assert_eq!(s.get(0x7000, 3), Some(-5000));
}

#[test]
fn inputs_pack_ia_at_byte_10() {
    let mut s = crate::store();
    s.set(0x6000, 6, 750);
    s.set(0x6000, 1, 1);
    let inp = <ProcessImage>::build(&s, Direction::Inputs, &crate::DEVICE.process_data).unwrap();
    let mut buf = [0u8; 14];
    inp.pack(&s, &mut buf);
    assert_eq!(buf[0], 1);
    // 0x1A00 is 4 bytes; 0x1A02 W, C, U, IA -> IA at 4 + 6.
    assert_eq!(u16::from_le_bytes([buf[10], buf[11]]), 750);
}

#[test]
fn mixed_set_assignment_is_refused() {
    let mut s = crate::store();
    s.download(0x1C13, 2, &0x1A03u16.to_le_bytes(), AlState::PreOp)
        .unwrap();
    assert_eq!(
        <ProcessImage>::build(&s, Direction::Inputs, &crate::DEVICE.process_data),
        Err(PdoError::MixedSets(0x1A00, 0x1A03))
    );
}

#[test]
fn unknown_pdo_in_assignment_is_refused() {
    let mut s = crate::store();
    s.set(0x1C12, 1, 0x1234);
    assert_eq!(
        <ProcessImage>::build(&s, Direction::Outputs, &crate::DEVICE.process_data),
        Err(PdoError::UnknownPdo(0x1234))
    );
}

#[test]
fn bit_helpers_round_trip_unaligned_values() {
    let mut buf = [0u8; 4];
    write_bits(&mut buf, 3, 5, 0b10110);
    assert_eq!(read_bits(&buf, 3, 5), 0b10110);
    write_bits(&mut buf, 8, 16, 0xBEEF);
    assert_eq!(read_bits(&buf, 8, 16), 0xBEEF);
    // Out of range is ignored, not a panic.
    write_bits(&mut buf, 30, 8, 0xFF);
    assert_eq!(read_bits(&buf, 40, 8), 0);
}
