//! SDO Information (core) describing the PAM's dictionary.

use ecat_slave::coe::sdo_info::*;
use ecat_slave::od::Object;

/// An SDO Info request: header (not fragmented) and service data.
fn request(opcode: u8, data: &[u8]) -> Vec<u8> {
    let mut v = vec![opcode, 0, 0, 0];
    v.extend_from_slice(data);
    v
}

/// All fragments of the response to `req`, each at most `size` bytes.
fn exchange(server: &mut SdoInfoServer, req: &[u8], size: usize) -> Vec<Vec<u8>> {
    let mut out = vec![0u8; size];
    let mut frames = Vec::new();
    let n = server
        .handle(req, &mut out, &crate::description::od::DICT)
        .expect("a response");
    frames.push(out[..n].to_vec());
    while let Some(n) = server.next_fragment(&mut out, &crate::description::od::DICT) {
        frames.push(out[..n].to_vec());
        assert!(frames.len() < 1000, "endless response");
    }
    assert!(!server.busy());
    frames
}

/// The service data of all fragments, checking the fragment headers.
fn reassemble(frames: &[Vec<u8>], opcode: u8) -> Vec<u8> {
    let mut data = Vec::new();
    let last = frames.len() - 1;
    for (i, f) in frames.iter().enumerate() {
        assert_eq!(f[0] & 0x7F, opcode, "fragment {i}");
        assert_eq!(f[0] & 0x80 != 0, i < last, "incomplete bit of {i}");
        assert_eq!(f[1], 0);
        assert_eq!(
            usize::from(u16::from_le_bytes([f[2], f[3]])),
            last - i,
            "fragments left of {i}"
        );
        data.extend_from_slice(&f[4..]);
    }
    data
}

fn words(data: &[u8]) -> Vec<u16> {
    data.chunks(2)
        .map(|c| u16::from_le_bytes([c[0], c[1]]))
        .collect()
}

fn od_list(list_type: u16, size: usize) -> Vec<u16> {
    let mut s = SdoInfoServer::new();
    let frames = exchange(&mut s, &request(1, &list_type.to_le_bytes()), size);
    let w = words(&reassemble(&frames, 2));
    assert_eq!(w[0], list_type);
    w[1..].to_vec()
}

fn entry_desc(index: u16, sub: u8, info: u8) -> Vec<u8> {
    let mut s = SdoInfoServer::new();
    let mut req = index.to_le_bytes().to_vec();
    req.extend([sub, info]);
    let frames = exchange(&mut s, &request(5, &req), 128);
    assert_eq!(frames.len(), 1);
    frames[0].clone()
}

fn error_code(frame: &[u8]) -> u32 {
    assert_eq!(frame.len(), 8);
    assert_eq!(&frame[..4], &[0x07, 0, 0, 0]);
    u32::from_le_bytes(frame[4..8].try_into().unwrap())
}

fn indices(pred: impl Fn(&Object) -> bool) -> Vec<u16> {
    crate::description::od::OBJECTS
        .iter()
        .filter(|o| pred(o))
        .map(|o| o.index)
        .collect()
}

#[test]
fn od_list_counts_give_the_size_of_each_list() {
    let mut s = SdoInfoServer::new();
    let frames = exchange(&mut s, &request(1, &[0, 0]), 128);
    assert_eq!(frames.len(), 1);
    let f = &frames[0];
    assert_eq!(&f[..4], &[0x02, 0, 0, 0]);
    let w = words(&f[4..]);
    let want = [
        crate::description::od::OBJECTS.len(),
        od_list(2, 128).len(),
        od_list(3, 128).len(),
        od_list(4, 128).len(),
        od_list(5, 128).len(),
    ];
    assert_eq!(w[0], 0);
    assert_eq!(
        w[1..].iter().map(|&n| usize::from(n)).collect::<Vec<_>>(),
        want
    );
    // 0x7000/0x7010/0x7020 are the only RxPDO objects; 12 settings objects.
    assert_eq!(w[2], 3);
    assert_eq!(w[4], 14);
    assert_eq!(w[4], w[5]);
}

#[test]
fn all_objects_list_is_the_model_in_order_across_small_fragments() {
    let all: Vec<u16> = crate::description::od::OBJECTS
        .iter()
        .map(|o| o.index)
        .collect();
    let mut s = SdoInfoServer::new();
    let frames = exchange(&mut s, &request(1, &[1, 0]), 20);
    assert!(frames.len() > 5, "{} fragments", frames.len());
    let w = words(&reassemble(&frames, 2));
    assert_eq!(w[0], 1);
    assert_eq!(w[1..], all[..]);
    // 16 bytes of service data per fragment: list type + 7, then 8 indices.
    assert_eq!(frames[0].len(), 20);
    assert_eq!(frames.len(), (2 + 2 * all.len()).div_ceil(16));
    // Big enough for everything: one fragment.
    assert_eq!(od_list(1, 1024), all);
}

#[test]
fn odd_fragment_sizes_never_split_an_index() {
    let all: Vec<u16> = crate::description::od::OBJECTS
        .iter()
        .map(|o| o.index)
        .collect();
    for size in [6, 7, 9, 21, 33] {
        let mut s = SdoInfoServer::new();
        let frames = exchange(&mut s, &request(1, &[1, 0]), size);
        assert!(frames.iter().all(|f| f.len() % 2 == 0), "size {size}");
        assert_eq!(words(&reassemble(&frames, 2))[1..], all[..], "size {size}");
    }
}

#[test]
fn rxpdo_list_holds_the_output_objects() {
    assert_eq!(od_list(2, 20), [0x7000, 0x7010, 0x7020]);
}

#[test]
fn txpdo_list_holds_timestamp_inputs_and_diagnosis() {
    assert_eq!(
        od_list(3, 20),
        [0x10F8, 0x6000, 0x6010, 0x6020, 0xA000, 0xA010, 0xA020]
    );
}

#[test]
fn backup_and_settings_lists_hold_the_stored_parameters() {
    let want =
        indices(|o| (0x8000..=0x8FFF).contains(&o.index) || matches!(o.index, 0xF800 | 0xF80F));
    assert_eq!(want.len(), 14);
    assert_eq!(od_list(4, 20), want);
    assert_eq!(od_list(5, 64), want);
}

#[test]
fn object_description_of_identity_is_a_record_of_four() {
    let mut s = SdoInfoServer::new();
    let frames = exchange(&mut s, &request(3, &[0x18, 0x10]), 128);
    let mut want = vec![0x04, 0, 0, 0, 0x18, 0x10, 0x23, 0x00, 4, 0x09];
    want.extend_from_slice(b"IDENTITY");
    assert_eq!(frames, [want]);
}

#[test]
fn object_descriptions_report_var_array_and_record_types() {
    let desc = |index: u16| {
        let mut s = SdoInfoServer::new();
        exchange(&mut s, &request(3, &index.to_le_bytes()), 128).remove(0)
    };
    // VAR: the entry's type; name after 10 bytes.
    let f = desc(0x1008);
    assert_eq!(&f[4..10], &[0x08, 0x10, 0x09, 0x00, 0, 0x07]);
    assert_eq!(&f[10..], b"DEVICE NAME");
    // ARRAY: the element type (UINT16), max sub 2.
    let f = desc(0x1C13);
    assert_eq!(&f[4..10], &[0x13, 0x1C, 0x06, 0x00, 2, 0x08]);
    // PDO mapping record and a generic record.
    assert_eq!(&desc(0x1A00)[6..10], &[0x21, 0x00, 0x0D, 0x09]);
    assert_eq!(&desc(0x800D)[6..10], &[0x2A, 0x00, 0x0A, 0x09]);
}

#[test]
fn entry_description_of_current_has_unit_default_min_max() {
    let f = entry_desc(0x800D, 0x02, 0x78);
    let mut want = vec![0x06, 0, 0, 0];
    want.extend([0x0D, 0x80, 0x02, 0x78]);
    want.extend([0x06, 0x00, 16, 0]); // UINT, 16 bits
    want.extend(0x033Fu16.to_le_bytes()); // RW | backup | setting
    want.extend(0xFD04_0000u32.to_le_bytes()); // mA
    want.extend(1000u16.to_le_bytes());
    want.extend(500u16.to_le_bytes());
    want.extend(3000u16.to_le_bytes());
    want.extend_from_slice(b"CURRENT");
    assert_eq!(f, want);
}

#[test]
fn entry_description_without_value_info_is_header_and_name() {
    let f = entry_desc(0x800D, 0x02, 0x00);
    assert_eq!(
        &f[4..14],
        &[0x0D, 0x80, 0x02, 0x00, 0x06, 0, 16, 0, 0x3F, 0x03]
    );
    assert_eq!(&f[14..], b"CURRENT");
    // Reserved value info bits are not echoed.
    assert_eq!(entry_desc(0x800D, 0x02, 0x87)[7], 0x00);
}

#[test]
fn entry_description_of_an_enum_reports_the_enum_type_and_its_range() {
    let f = entry_desc(0xF800, 0x02, 0x78);
    assert_eq!(&f[4..8], &[0x00, 0xF8, 0x02, 0x78]);
    assert_eq!(&f[8..12], &[0x00, 0x08, 3, 0]); // DT0800EN03, 3 bits
    assert_eq!(&f[12..14], &0x033Fu16.to_le_bytes()); // RW, backup, setting
    assert_eq!(&f[14..18], &[0, 0, 0, 0]); // no unit
    assert_eq!(&f[18..21], &[1, 1, 2]); // default DIRECTIONAL, 1..=2
    assert_eq!(&f[21..], b"FUNCTION");
}

#[test]
fn entry_description_of_a_write_only_entry_has_access_0x0038() {
    let f = entry_desc(0xF801, 0x01, 0x00);
    assert_eq!(&f[8..14], &[0x07, 0x00, 32, 0, 0x38, 0x00]);
    assert_eq!(&f[14..], b"PASSWORD");
}

#[test]
fn entry_description_of_a_gap_is_null_with_no_access_and_no_values() {
    let f = entry_desc(0x6000, 0x02, 0x78);
    // Value info cleared, type 0x0000 (NULL), 7 bits, access 0.
    assert_eq!(f[7], 0x00);
    assert_eq!(&f[8..14], &[0x00, 0x00, 7, 0, 0x00, 0x00]);
    assert_eq!(&f[14..], b"SubIndex 002");
}

#[test]
fn entry_description_of_pdo_entries_sets_the_mapping_bits() {
    let f = entry_desc(0x7000, 0x03, 0x60);
    assert_eq!(&f[8..14], &[0x04, 0x00, 32, 0, 0x7F, 0x00]);
    assert_eq!(&f[14..18], &i32::MIN.to_le_bytes());
    assert_eq!(&f[18..22], &i32::MAX.to_le_bytes());
    let f = entry_desc(0x10F8, 0x00, 0x40);
    assert_eq!(&f[8..14], &[0x1B, 0x00, 64, 0, 0x87, 0x00]);
    assert_eq!(&f[14..22], &[0xFF; 8]); // UINT64 maximum
    assert_eq!(&f[22..], b"Timestamp Object");
}

#[test]
fn entry_description_of_a_string_sends_its_text_and_no_range() {
    let f = entry_desc(0x1008, 0x00, 0x78);
    assert_eq!(f[7], 0x18); // min/max dropped
    assert_eq!(&f[8..14], &[0x09, 0x00, 104, 0, 0x07, 0x00]);
    assert_eq!(&f[18..31], b"PAM-199-P-ETC");
    assert_eq!(&f[31..], b"DEVICE NAME");
}

#[test]
fn signed_values_are_sign_extended_to_the_entry_size() {
    let f = entry_desc(0x8006, 0x01, 0x70);
    assert_eq!(&f[14..20], &[0xF0, 0xD8, 0xF0, 0xD8, 0x10, 0x27]); // -10000 x2, 10000
}

#[test]
fn unknown_object_answers_object_does_not_exist() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 64];
    let n = s
        .handle(
            &request(3, &[0x02, 0x10]),
            &mut out,
            &crate::description::od::DICT,
        )
        .unwrap();
    assert_eq!(error_code(&out[..n]), 0x0602_0000);
    let n = s
        .handle(
            &request(5, &[0x00, 0x08, 0, 0]),
            &mut out,
            &crate::description::od::DICT,
        )
        .unwrap();
    assert_eq!(error_code(&out[..n]), 0x0602_0000); // enum types are not objects
    assert!(!s.busy());
}

#[test]
fn unknown_or_absent_subindex_answers_subindex_does_not_exist() {
    for (index, sub) in [(0x1018u16, 5u8), (0x8002, 1), (0x1000, 1)] {
        let mut req = index.to_le_bytes().to_vec();
        req.extend([sub, 0]);
        let mut s = SdoInfoServer::new();
        let mut out = [0u8; 64];
        let n = s
            .handle(&request(5, &req), &mut out, &crate::description::od::DICT)
            .unwrap();
        assert_eq!(error_code(&out[..n]), 0x0609_0011, "{index:#06x}:{sub}");
    }
}

#[test]
fn truncated_or_unknown_requests_answer_unknown_command() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 64];
    for req in [
        vec![],
        vec![0x01, 0, 0],
        request(1, &[]),
        request(1, &[1]),
        request(3, &[0x18]),
        request(5, &[0x18, 0x10, 0x01]),
        request(1, &[6, 0]), // unknown list type
        request(2, &[1, 0]), // a response opcode
        request(0x7F, &[]),  // unknown opcode
    ] {
        let n = s
            .handle(&req, &mut out, &crate::description::od::DICT)
            .unwrap();
        assert_eq!(error_code(&out[..n]), 0x0504_0001, "{req:02x?}");
    }
}

#[test]
fn fragments_left_count_down_to_zero() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 10]; // 6 bytes of service data per fragment
    let n = s
        .handle(
            &request(1, &[1, 0]),
            &mut out,
            &crate::description::od::DICT,
        )
        .unwrap();
    assert_eq!(n, 10);
    let total = 2 + 2 * crate::description::od::OBJECTS.len();
    let count = total.div_ceil(6);
    let mut left = vec![u16::from_le_bytes([out[2], out[3]])];
    assert!(out[0] & 0x80 != 0 && s.busy());
    while s
        .next_fragment(&mut out, &crate::description::od::DICT)
        .is_some()
    {
        left.push(u16::from_le_bytes([out[2], out[3]]));
    }
    let want: Vec<u16> = (0..count as u16).rev().collect();
    assert_eq!(left, want);
    assert_eq!(out[0], 0x02); // last: incomplete bit clear
    assert_eq!(
        s.next_fragment(&mut out, &crate::description::od::DICT),
        None
    );
}

#[test]
fn buffered_descriptions_fragment_too() {
    let whole = entry_desc(0x800D, 0x02, 0x78);
    let mut s = SdoInfoServer::new();
    let frames = exchange(&mut s, &request(5, &[0x0D, 0x80, 0x02, 0x78]), 9);
    assert_eq!(frames.len(), (whole.len() - 4).div_ceil(5));
    assert_eq!(reassemble(&frames, 6), whole[4..]);
}

#[test]
fn a_new_request_abandons_the_pending_response() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 12];
    s.handle(
        &request(1, &[1, 0]),
        &mut out,
        &crate::description::od::DICT,
    )
    .unwrap();
    assert!(s.busy());
    // 0x1000's description: 6 + 11 bytes in fragments of 8, 8, 1.
    let n = s
        .handle(
            &request(3, &[0x00, 0x10]),
            &mut out,
            &crate::description::od::DICT,
        )
        .unwrap();
    assert_eq!(&out[..n], b"\x84\x00\x02\x00\x00\x10\x07\x00\x00\x07DE");
    let n = s
        .next_fragment(&mut out, &crate::description::od::DICT)
        .unwrap();
    assert_eq!(&out[..n], b"\x84\x00\x01\x00VICE TYP");
    let n = s
        .next_fragment(&mut out, &crate::description::od::DICT)
        .unwrap();
    assert_eq!(&out[..n], b"\x04\x00\x00\x00E");
    assert_eq!(
        s.next_fragment(&mut out, &crate::description::od::DICT),
        None
    );
}

#[test]
fn too_small_output_gives_no_response_and_no_state() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 5];
    assert_eq!(
        s.handle(
            &request(1, &[1, 0]),
            &mut out,
            &crate::description::od::DICT
        ),
        None
    );
    assert!(!s.busy());
    assert_eq!(
        s.handle(
            &request(3, &[0x02, 0x10]),
            &mut out,
            &crate::description::od::DICT
        ),
        None
    );
    let mut big = [0u8; 20];
    s.handle(
        &request(1, &[1, 0]),
        &mut big,
        &crate::description::od::DICT,
    )
    .unwrap();
    assert!(s.busy());
    assert_eq!(
        s.next_fragment(&mut out, &crate::description::od::DICT),
        None
    );
    assert!(!s.busy());
}

#[test]
fn every_entry_has_a_description_that_fits_the_buffer() {
    let mut s = SdoInfoServer::new();
    let mut out = [0u8; 4 + INFO_BUFFER];
    for o in crate::description::od::OBJECTS {
        for e in o.entries {
            let mut req = o.index.to_le_bytes().to_vec();
            req.extend([e.sub, value_info::ALL]);
            let n = s
                .handle(&request(5, &req), &mut out, &crate::description::od::DICT)
                .unwrap();
            assert_eq!(out[0], 0x06, "{:#06x}:{}", o.index, e.sub);
            assert!(out[n - e.name.len()..n] == *e.name.as_bytes());
        }
    }
}
