//! SDO access through ethercrab's own CoE client.

use crate::common::abort_code;
use master_test::VirtualBus;

#[test]
fn sdo_reads_identity_and_writes_current_with_range_checks() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");

        let product: u32 = sd.sdo_read(0x1018, 2).await.expect("0x1018:02");
        assert_eq!(product, 0x00C7_03F3);

        sd.sdo_write(0x800D, 2, 2000u16)
            .await
            .expect("CURRENT = 2000");
        let current: u16 = sd.sdo_read(0x800D, 2).await.expect("read CURRENT");
        assert_eq!(current, 2000);

        let e = sd
            .sdo_write(0x800D, 2, 5000u16)
            .await
            .expect_err("5000 mA is above 3000");
        assert_eq!(abort_code(&e), Some(0x0609_0031));
        let current: u16 = sd.sdo_read(0x800D, 2).await.expect("read CURRENT");
        assert_eq!(current, 2000, "a refused write leaves the value");

        let e = sd
            .sdo_write(0x1018, 1, 1u32)
            .await
            .expect_err("identity is read-only");
        assert_eq!(abort_code(&e), Some(0x0601_0002));

        let e = sd
            .sdo_read::<u32>(0x1234, 0)
            .await
            .expect_err("no such object");
        assert_eq!(abort_code(&e), Some(0x0602_0000));
    });
}

#[test]
fn sdo_length_and_access_errors_carry_their_abort_codes() {
    smol::block_on(async {
        let bus = VirtualBus::new(1).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");

        let e = sd
            .sdo_write(0x800D, 2, 1000u32)
            .await
            .expect_err("4 bytes into a UINT");
        assert_eq!(abort_code(&e), Some(0x0607_0012));
        let e = sd
            .sdo_write(0x8002, 2, 100u16)
            .await
            .expect_err("2 bytes into a UDINT");
        assert_eq!(abort_code(&e), Some(0x0607_0013));
        let e = sd
            .sdo_write(0x800D, 2, 100u16)
            .await
            .expect_err("below 500 mA");
        assert_eq!(abort_code(&e), Some(0x0609_0032));
        let e = sd
            .sdo_write(0xF800, 2, 9u8)
            .await
            .expect_err("not a FUNCTION value");
        assert_eq!(abort_code(&e), Some(0x0609_0030));
        let e = sd
            .sdo_read::<u32>(0xF801, 1)
            .await
            .expect_err("PASSWORD is write-only");
        assert_eq!(abort_code(&e), Some(0x0601_0001));
        let e = sd
            .sdo_read::<u16>(0x1018, 7)
            .await
            .expect_err("no subindex 7");
        assert_eq!(abort_code(&e), Some(0x0609_0011));
        let name: heapless::String<32> = sd.sdo_read(0x1008, 0).await.expect("device name");
        assert_eq!(name.as_str(), "PAM-199-P-ETC");
        // 0x10F8 timestamp counts while the slave runs (manual 7.2).
        let t1: u64 = sd.sdo_read(0x10F8, 0).await.expect("timestamp");
        smol::Timer::after(std::time::Duration::from_millis(5)).await;
        let t2: u64 = sd.sdo_read(0x10F8, 0).await.expect("timestamp");
        assert!(t2 > t1, "0x10F8 advances: {t1} then {t2}");
    });
}

/// Property (proptest, 512 cases on one live slave in PRE-OP): an SDO
/// download followed by an upload of the same entry gives the written
/// value when the download was acknowledged and the old value when it was
/// aborted: never part of it (single entries and complete access, short
/// and segmented transfers, lengths right and wrong, read-only, absent and
/// out-of-range targets).
#[test]
#[allow(
    clippy::await_holding_refcell_ref,
    reason = "each case runs alone in block_on: no other borrow can happen"
)]
fn sdo_download_then_upload_gives_the_value_or_an_abort_never_half_of_it() {
    use master_test::mailbox::{MailboxClient, MailboxGeometry};
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestCaseError, TestRunner};

    /// (index, subindex, complete access).
    const TARGETS: &[(u16, u8, bool)] = &[
        (0x800D, 2, false),    // CURRENT, UINT 500..3000
        (0x800D, 5, false),    // PWM, enum
        (0x800A, 0, true),     // the whole deadband record (with gaps)
        (0x800A, 1, true),     // from subindex 1
        (0x8002, 0, true),     // the ramp record
        (0x8006, 0x2A, false), // a curve point, INT
        (0x8006, 0, true),     // the whole 42-point curve (segmented)
        (0x800A, 1, false),    // CCMODE, BOOL
        (0x8002, 2, false),    // RA:UP:A, UDINT
        (0xF800, 3, false),    // SENS
        (0x1C12, 1, false),    // RxPDO assignment
        (0x1600, 0, true),     // a mapping object
        (0x1018, 1, false),    // identity, read-only
        (0x1008, 0, false),    // device name, read-only string
        (0x6000, 1, false),    // an input, read-only
        (0x2000, 0, false),    // absent
        (0x800D, 0x30, false), // absent subindex
    ];

    /// The bits of a transfer of `len` bytes that carry values: not the
    /// padding byte after subindex 0 of a complete access (ETG.1000.6
    /// 5.6.2.1.2: subindex 0 takes 16 bits) and not the padding gaps of a
    /// record, which read as 0 whatever was written.
    fn cared_bits(index: u16, sub: u8, ca: bool, len: usize) -> Vec<bool> {
        let mut care = vec![true; len * 8];
        if !ca {
            return care;
        }
        let (_, obj) = pam_199_p_etc::od::find(index).expect("a complete access target exists");
        let mut bit = 0usize;
        for e in obj.entries.iter().filter(|e| e.sub >= sub) {
            let size = if e.sub == 0 {
                16
            } else {
                usize::from(e.bit_len)
            };
            let skip = if e.sub == 0 {
                8..16
            } else if e.gap() {
                0..size
            } else {
                0..0
            };
            for b in skip {
                if let Some(c) = care.get_mut(bit + b) {
                    *c = false;
                }
            }
            bit += size;
        }
        care
    }

    let bus = VirtualBus::new(1).expect("bus");
    let md = &*bus.maindevice;
    smol::block_on(bus.init()).expect("PRE-OP");
    let client =
        std::cell::RefCell::new(MailboxClient::new(md, 0x1000, MailboxGeometry::standard()));
    let strategy = (
        prop::sample::select(TARGETS),
        prop::collection::vec(any::<u8>(), 200),
        0usize..=12,
        0u8..4,
        any::<bool>(),
    );
    let mut runner = TestRunner::new(Config::with_cases(512));
    let (acked, aborted) = (std::cell::Cell::new(0u32), std::cell::Cell::new(0u32));
    let result = runner.run(
        &strategy,
        |((index, sub, ca), bytes, short_len, shape, force_normal)| {
            smol::block_on(async {
                let mut client = client.borrow_mut();
                let old = client.sdo_upload(index, sub, ca).await;
                // The data: random bytes of a random length (shape 0), of
                // the entry's length (1), the value read (2: a write that
                // can succeed), or the value read with a small change in
                // one byte (3: often in range, sometimes not).
                let data: Vec<u8> = match (&old, shape) {
                    (Ok(v), 1) => bytes[..v.len().min(bytes.len())].to_vec(),
                    (Ok(v), 2) => v.clone(),
                    (Ok(v), 3) if !v.is_empty() => {
                        let mut d = v.clone();
                        let i = usize::from(bytes[0]) % d.len();
                        d[i] ^= bytes[1] & 0x0F;
                        d
                    }
                    _ => bytes[..short_len].to_vec(),
                };
                let data = &data[..];
                let written = client
                    // (An expedited transfer cannot carry 0 bytes.)
                    .sdo_download_with(index, sub, ca, data, force_normal || data.is_empty())
                    .await;
                let new = client.sdo_upload(index, sub, ca).await;
                let at = format!("{index:#06x}:{sub:02x} ca={ca} {data:02x?}");
                match written {
                    Ok(()) => {
                        acked.set(acked.get() + 1);
                        let new = new.map_err(|e| {
                            TestCaseError::fail(format!(
                                "{at}: upload after an acknowledged write: {e}"
                            ))
                        })?;
                        let care = cared_bits(index, sub, ca, data.len());
                        let differs = (0..data.len() * 8).any(|bit| {
                            let (byte, m) = (bit / 8, 1u8 << (bit % 8));
                            care[bit]
                                && (new.get(byte).copied().unwrap_or(!data[byte]) ^ data[byte]) & m
                                    != 0
                        });
                        prop_assert!(
                            new.len() == data.len() && !differs,
                            "{}: acknowledged, then read back {:02x?}",
                            at,
                            new
                        );
                    }
                    Err(e) => {
                        prop_assert!(
                            e.abort_code().is_some(),
                            "{}: the download failed without an abort: {}",
                            at,
                            e
                        );
                        aborted.set(aborted.get() + 1);
                        match (&old, &new) {
                            (Ok(o), Ok(n)) => prop_assert_eq!(o, n, "{}: aborted, yet changed", at),
                            (Err(a), Err(b)) => {
                                prop_assert_eq!(a.abort_code(), b.abort_code(), "{}", at)
                            }
                            _ => prop_assert!(
                                false,
                                "{}: readability changed: {:?} / {:?}",
                                at,
                                old,
                                new
                            ),
                        }
                    }
                }
                Ok(())
            })
        },
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    let (acked, aborted) = (acked.get(), aborted.get());
    eprintln!("SDO property: {acked} writes acknowledged, {aborted} aborted");
    assert!(
        acked >= 5 && aborted >= 5,
        "both outcomes exercised: {acked} / {aborted}"
    );
}
