//! CoE through the test master's own mailbox client: complete access,
//! segmented transfers, mailbox errors and counters.

use ecat_slave::wire::coe::SdoAbortCode;
use ecat_slave::wire::mailbox::{MailboxErrorCode, MailboxType};
use master_test::VirtualBus;
use master_test::mailbox::{ClientError, MailboxClient, MailboxGeometry};

#[test]
fn complete_access_reads_and_writes_all_42_curve_points_in_one_transfer() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::standard());
        let img = c.sdo_upload(0x8006, 0, true).await.expect("CA upload");
        assert_eq!(img.len(), 86);
        assert_eq!((img[0], img[1]), (42, 0));
        assert_eq!(i16::from_le_bytes([img[2], img[3]]), -10000);
        let mut new = img.clone();
        for i in 0..42 {
            let v = (i as i16 - 21) * 300;
            new[2 + 2 * i..4 + 2 * i].copy_from_slice(&v.to_le_bytes());
        }
        c.sdo_download(0x8006, 0, true, &new)
            .await
            .expect("CA download");
        assert_eq!(c.sdo_upload(0x8006, 0, true).await.expect("read back"), new);
        let p: i16 = sd.sdo_read(0x8006, 0x2A).await.expect("single read");
        assert_eq!(p, 20 * 300);
        // One point out of range: refused and nothing changes.
        let mut bad = new.clone();
        bad[4..6].copy_from_slice(&(-12000i16).to_le_bytes());
        let e = c
            .sdo_download(0x8006, 0, true, &bad)
            .await
            .expect_err("out of range");
        assert_eq!(e.abort_code(), Some(0x0609_0032));
        assert_eq!(c.sdo_upload(0x8006, 0, true).await.expect("unchanged"), new);
    });
}

#[test]
fn pdo_assignment_complete_access_is_accepted_in_preop_only() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        // 0x1C13 = { 0x1A00, 0x1A02 } written whole in PRE-OP.
        c.sdo_download(0x1C13, 0, true, &[2, 0, 0x00, 0x1A, 0x02, 0x1A])
            .await
            .expect("PRE-OP");
        c.sdo_download(0x1C12, 0, true, &[1, 0, 0x00, 0x16])
            .await
            .expect("PRE-OP");
        let e = c
            .sdo_download(0x1C13, 0, true, &[2, 0, 0x00, 0x1A, 0x34, 0x12])
            .await
            .expect_err("0x1234 is no TxPDO");
        assert_eq!(e.abort_code(), Some(0x0609_0030));
        let group = group.into_safe_op(md).await.expect("safe-op");
        for (state, index, img) in [
            ("SAFE-OP", 0x1C13, &[2u8, 0, 0x00, 0x1A, 0x02, 0x1A][..]),
            ("SAFE-OP", 0x1C12, &[1u8, 0, 0x00, 0x16][..]),
        ] {
            let e = c.sdo_download(index, 0, true, img).await.expect_err(state);
            assert_eq!(e.abort_code(), Some(0x0800_0022), "{state} {index:#x}");
        }
        let group = group.into_op(md).await.expect("op");
        let e = c
            .sdo_download(0x1C13, 0, true, &[2, 0, 0x00, 0x1A, 0x02, 0x1A])
            .await
            .expect_err("OP");
        assert_eq!(e.abort_code(), Some(0x0800_0022));
        drop(group);
    });
}

/// The PAM's mappings are fixed (every entry of 0x16xx/0x1Axx read-only):
/// a complete access writing back what a mapping holds changes nothing and
/// is acknowledged in any state with a mailbox; one changing a value is
/// refused as read-only, and the mapping stays as it was. (The mapping
/// rules for writable mappings, PRE-OP only among them, are tested on the
/// CiA 402 drive, tests/it/servo402.rs.)
#[test]
fn a_fixed_mapping_takes_its_own_values_back_and_refuses_others_in_every_state() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        let held = c.sdo_upload(0x1A00, 0, true).await.expect("the mapping");
        let mut changed = held.clone();
        // The first mapped entry's bit length (byte 2 of the image: after
        // subindex 0's 16 bits).
        changed[2] ^= 0x08;
        check(&mut c, "PRE-OP", &held, &changed).await;
        let group = group.into_safe_op(md).await.expect("safe-op");
        check(&mut c, "SAFE-OP", &held, &changed).await;
        let group = group.into_op(md).await.expect("op");
        check(&mut c, "OP", &held, &changed).await;
        drop(group);
    });

    async fn check(c: &mut MailboxClient<'_>, state: &str, held: &[u8], changed: &[u8]) {
        c.sdo_download(0x1A00, 0, true, held)
            .await
            .unwrap_or_else(|e| panic!("{state}: its own values: {e}"));
        let e = c
            .sdo_download(0x1A00, 0, true, changed)
            .await
            .expect_err(state);
        assert_eq!(e.abort_code(), Some(0x0601_0002), "{state}");
        assert_eq!(
            c.sdo_upload(0x1A00, 0, true).await.unwrap(),
            held,
            "{state}"
        );
    }
}

#[test]
fn segmented_download_writes_and_an_interrupted_one_leaves_the_object_unchanged() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        // Every RW entry through the segmented path: RA:UP:A (UDINT).
        c.sdo_download_with(0x8002, 2, false, &5000u32.to_le_bytes(), true)
            .await
            .expect("segmented download");
        assert_eq!(
            c.sdo_upload(0x8002, 2, false).await.unwrap(),
            5000u32.to_le_bytes()
        );
        // Interrupted: initiate with 4 of 4 announced bytes missing, then a
        // new request abandons it.
        c.begin_download(0x8002, 3, 4, &[]).await.expect("initiate");
        let e = c
            .sdo_upload(0x8002, 3, false)
            .await
            .expect_err("abandoned transfer");
        assert_eq!(e.abort_code(), Some(u32::from(SdoAbortCode::Timeout)));
        assert_eq!(
            c.sdo_upload(0x8002, 3, false).await.unwrap(),
            100u32.to_le_bytes(),
            "unchanged"
        );
        // A wrong toggle bit aborts 0x05030000 and leaves the object.
        c.begin_download(0x8002, 3, 4, &[]).await.expect("initiate");
        let e = c
            .download_segment(true, true, &[1, 0, 0, 0])
            .await
            .expect_err("toggle");
        assert_eq!(e.abort_code(), Some(0x0503_0000));
        assert_eq!(
            c.sdo_upload(0x8002, 3, false).await.unwrap(),
            100u32.to_le_bytes()
        );
    });
}

#[test]
fn malformed_mailboxes_get_error_replies_and_repeated_counters_run_once() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        // Length field beyond the mailbox.
        let mut buf = vec![0u8; 128];
        buf[0] = 0xFF;
        buf[5] = 0x03 | (1 << 4);
        c.write_buffer(&buf).await.expect("write");
        let m = c.receive().await.expect("reply");
        assert_eq!(m.kind, MailboxType::Error);
        assert_eq!(
            u16::from_le_bytes([m.payload[2], m.payload[3]]),
            0x08,
            "invalid size"
        );
        // Unknown mailbox type.
        c.send(MailboxType::Unknown(0x0E), &[1, 2, 3])
            .await
            .expect("send");
        let m = c.receive().await.expect("reply");
        assert_eq!(m.kind, MailboxType::Error);
        // CoE service that does not exist.
        c.send(MailboxType::CoE, &[0x00, 0xF0, 0, 0, 0, 0, 0, 0, 0, 0])
            .await
            .expect("send");
        let m = c.receive().await.expect("reply");
        assert_eq!(m.kind, MailboxType::Error);
        // The same mailbox twice (counter and content): executed once. SAVE
        // shows it: a second execution would write the EEPROM again (and be
        // refused by the SAVE rate limit).
        let save = [0x00, 0x20, 0x23, 0x01, 0xF8, 0x02, 1, 0, 0, 0];
        let eeprom_writes = || {
            master_test::link::lock(&bus.chain).slaves()[0]
                .nv()
                .expect("the PAM stores parameters")
                .write_count()
        };
        c.send_raw(MailboxType::CoE, 5, &save).await.expect("send");
        c.receive().await.expect("ack");
        let after_save = eeprom_writes();
        assert!(after_save > 0, "the SAVE wrote the EEPROM");
        c.send_raw(MailboxType::CoE, 5, &save)
            .await
            .expect("send again");
        assert!(
            c.receive().await.is_err(),
            "no second response: not executed again"
        );
        assert_eq!(
            eeprom_writes(),
            after_save,
            "EEPROM written by one SAVE only"
        );
        // Same counter, different content (another master's sequence): served.
        let read = [0x00, 0x20, 0x40, 0x18, 0x10, 0x02, 0, 0, 0, 0];
        c.send_raw(MailboxType::CoE, 5, &read).await.expect("send");
        assert!(c.receive().await.is_ok(), "not taken for a repeat");
        let e = ClientError::Mailbox(MailboxErrorCode::InvalidSize);
        assert!(e.to_string().contains("mailbox error"));
    });
}

/// A valid value other than the default for an RW entry of `dict`, as
/// bytes.
fn other_value(
    e: &ecat_slave::od::types::Entry,
    dict: &ecat_slave::od::Dictionary,
) -> Option<Vec<u8>> {
    use ecat_slave::od::types::DataType;
    let d = e.default_value().as_int()?;
    let v = match e.data_type {
        DataType::Bool => 1 - d,
        DataType::Enum(en) => dict
            .find_enum(en.index())?
            .values
            .iter()
            .map(|(v, _)| *v)
            .find(|v| *v != d)?,
        _ => match (e.min(), e.max()) {
            (_, Some(max)) if max != d => max,
            (Some(min), _) if min != d => min,
            _ => d ^ 1,
        },
    };
    let n = usize::from(e.bit_len).div_ceil(8);
    Some(v.to_le_bytes()[..n].to_vec())
}

#[test]
fn every_entry_reads_its_default_and_every_rw_entry_round_trips_both_paths() {
    use ecat_slave::od::types::Access;
    use pam_199_p_etc::od as model;
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        let defaults = pam_199_p_etc::store();
        let (mut read, mut written) = (0, 0);
        for obj in model::OBJECTS {
            for e in obj.entries {
                if e.gap() || !e.access().readable() || obj.index == 0x10F8 {
                    continue;
                }
                let (flat, _) = model::find_entry(obj.index, e.sub).unwrap();
                let mut want = [0u8; 64];
                let n = defaults.encode(flat, e, &mut want).unwrap();
                let got = c.sdo_upload(obj.index, e.sub, false).await.expect("upload");
                assert_eq!(got, &want[..n], "{:#06x}:{} default", obj.index, e.sub);
                read += 1;
            }
        }
        for obj in model::OBJECTS {
            // Commands, password-gated settings and PDO assignment have
            // their own tests; ACC locks the controller gains.
            if matches!(obj.index, 0xF801 | 0xF80F | 0x1C12 | 0x1C13) {
                continue;
            }
            for e in obj.entries {
                let gains =
                    matches!(obj.index, 0x800D | 0x801D | 0x802D) && matches!(e.sub, 9 | 10);
                if e.gap() || e.access() != Access::Rw || gains {
                    continue;
                }
                let v = other_value(e, &model::DICT).expect("every RW entry here is numeric");
                for segmented in [false, true] {
                    c.sdo_download_with(obj.index, e.sub, false, &v, segmented)
                        .await
                        .unwrap_or_else(|err| panic!("{:#06x}:{} write: {err}", obj.index, e.sub));
                    let back = c
                        .sdo_upload(obj.index, e.sub, false)
                        .await
                        .expect("read back");
                    assert_eq!(
                        back, v,
                        "{:#06x}:{} segmented={segmented}",
                        obj.index, e.sub
                    );
                    let (flat, _) = model::find_entry(obj.index, e.sub).unwrap();
                    let mut d = [0u8; 8];
                    let n = defaults.encode(flat, e, &mut d).unwrap();
                    c.sdo_download_with(obj.index, e.sub, false, &d[..n], !segmented)
                        .await
                        .expect("restore");
                }
                written += 1;
            }
        }
        let readable = model::OBJECTS
            .iter()
            .filter(|o| o.index != 0x10F8)
            .flat_map(|o| o.entries.iter())
            .filter(|e| !e.gap() && e.access().readable())
            .count();
        assert_eq!(read, readable, "every readable entry was read");
        assert!(written > 100, "{written} RW entries written on both paths");
    });
}

#[test]
fn an_injected_fault_produces_an_emergency_the_master_decodes() {
    use ecat_slave::wire::coe::{CoeHeader, CoeService, Emergency, EmergencyRepr};
    use master_test::link::lock;
    use pam_199_p_etc::board::{Fault, Solenoid};
    smol::block_on(async {
        // Simulated time: 1 ms per cycle, so no SM watchdog trip on a slow
        // machine can put another emergency first.
        let bus = VirtualBus::with_clock(1, master_test::link::Clock::simulated()).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let station = group.subdevice(md, 0).expect("slave").configured_address();
        let group = group.into_op(md).await.expect("op");
        for _ in 0..50 {
            let sd = group.subdevice(md, 0).unwrap();
            let mut out = sd.outputs_raw_mut();
            out[0] = 1;
            out[1..5].copy_from_slice(&5000i32.to_le_bytes());
            drop(out);
            bus.clock.advance(std::time::Duration::from_millis(1));
            group.tx_rx(md).await.unwrap();
        }
        lock(&bus.chain)
            .slave_mut::<pam_199_p_etc::Pam>(0)
            .expect("a PAM")
            .slave_mut()
            .app_mut()
            .stage_mut()
            .inject(Fault::ShortCircuit(Solenoid::A));
        let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
        let mut got = None;
        for _ in 0..20 {
            bus.clock.advance(std::time::Duration::from_millis(1));
            group.tx_rx(md).await.unwrap();
            if let Ok(m) = c.receive().await {
                got = Some(m);
                break;
            }
        }
        let m = got.expect("an emergency arrives");
        assert_eq!(m.kind, MailboxType::CoE);
        let coe = CoeHeader::new_checked(&m.payload[..]).unwrap();
        assert_eq!(coe.service(), CoeService::Emergency);
        let e = EmergencyRepr::parse(&Emergency::new_checked(&m.payload[2..]).unwrap()).unwrap();
        assert_eq!(e.error_code, 0x2320, "short circuit");
        assert_eq!(e.error_register, 0x03, "generic + current");
        assert_eq!(e.data[0], 1, "solenoid A");
        let reg = c.sdo_upload(0x1001, 0, false).await.expect("0x1001");
        assert_eq!(reg, [0x03], "error register consistent");
    });
}

#[test]
fn a_48_byte_mailbox_is_advertised_in_the_sii_and_long_uploads_are_segmented() {
    use ecat_sim::SoftSlave;
    use ecat_slave::device::MemoryLayout;
    use master_test::link::{Chain, Clock};
    let pam = pam_199_p_etc::DEVICE.layout();
    let layout = pam.with_mailbox_size(48).expect("valid size");
    assert!(pam.with_mailbox_size(8).is_none());
    assert!(pam.with_mailbox_size(4096).is_none());
    let _ = MemoryLayout::new(48, None).expect("a layout without BOOT");
    smol::block_on(async {
        let chain = Chain::with_slaves(vec![Box::new(SoftSlave::with_layout(
            pam_199_p_etc::Pam::default(),
            layout,
        ))]);
        let bus = VirtualBus::with_chain(chain, Clock::frames(), None).expect("bus");
        let md = &*bus.maindevice;
        let group = bus
            .init()
            .await
            .expect("ethercrab reads the small mailbox from the SII");
        let sd = group.subdevice(md, 0).expect("slave");
        let product: u32 = sd
            .sdo_read(0x1018, 2)
            .await
            .expect("expedited via ethercrab");
        assert_eq!(product, 0x00C7_03F3);
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::of(&layout));
        // 86 bytes do not fit a 48-byte mailbox: normal upload + segments.
        let img = c
            .sdo_upload(0x8006, 0, true)
            .await
            .expect("segmented upload");
        assert_eq!(img.len(), 86);
        assert_eq!(i16::from_le_bytes([img[84], img[85]]), 10000);
        let name = c
            .sdo_upload(0x1008, 0, false)
            .await
            .expect("13-byte string");
        assert_eq!(name, b"PAM-199-P-ETC");
        // And a segmented download of the same 86 bytes.
        c.sdo_download(0x8006, 0, true, &img)
            .await
            .expect("segmented download");
        let group = group
            .into_op(md)
            .await
            .expect("process data with the moved buffers");
        assert_eq!(group.tx_rx(md).await.expect("cycle").working_counter, 3);
    });
}

#[test]
fn od_dump_of_a_fresh_slave_has_no_error_rows_and_padding_agrees_everywhere() {
    use master_test::od::{EntryValue, read_dictionary};
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::standard());
        let dict = read_dictionary(&mut c).await.expect("dictionary");
        let mut values = 0;
        let mut padding = Vec::new();
        for o in &dict {
            for e in &o.entries {
                match &e.value {
                    EntryValue::Error(msg) => panic!(
                        "{:#06x}:{} {}: {msg}",
                        e.info.index, e.info.sub, e.info.name
                    ),
                    EntryValue::Padding => padding.push((e.info.index, e.info.sub)),
                    EntryValue::Value(_) => values += 1,
                    EntryValue::WriteOnly => {}
                }
            }
        }
        assert!(values > 270, "{values} values read");
        assert_eq!(padding.len(), 18, "{padding:x?}");
        // What SDO Information calls padding, an upload refuses with
        // 0x06010000 (unsupported access), as the SSC does.
        for (index, sub) in padding {
            let e = c
                .sdo_upload(index, sub, false)
                .await
                .expect_err("padding is not readable");
            assert_eq!(e.abort_code(), Some(0x0601_0000), "{index:#06x}:{sub}");
        }
    });
}

#[test]
fn an_abort_travels_in_coe_service_2_as_etg_1000_6_and_soem_expect() {
    use ecat_slave::wire::coe::{CoeHeader, CoeService, SdoRequest};
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::standard());
        // Upload request for 0x1234:00, sent by hand.
        let mut req = [0u8; 10];
        CoeHeader::emit_into(&mut req[..2], 0, CoeService::SdoRequest);
        SdoRequest::InitiateUpload {
            index: 0x1234,
            sub: 0,
            complete_access: false,
        }
        .emit(&mut req[2..])
        .unwrap();
        c.send(MailboxType::CoE, &req).await.expect("send");
        let m = c.receive().await.expect("answer");
        let coe = CoeHeader::new_checked(&m.payload[..]).unwrap();
        assert_eq!(coe.service(), CoeService::SdoRequest, "abort = SDO request");
        assert_eq!(
            SdoRequest::parse(&m.payload[2..]).unwrap(),
            SdoRequest::Abort {
                index: 0x1234,
                sub: 0,
                code: SdoAbortCode::ObjectNotFound
            }
        );
    });
}
