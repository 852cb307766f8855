//! pcap capture of the virtual link: every frame in both directions, in a
//! file Wireshark's EtherCAT dissector reads.

use ecat_sim::pcap::read_all;
use master_test::VirtualBus;
use master_test::link::Clock;
use std::process::Command;

#[test]
fn virtual_link_capture_holds_requests_and_replies_of_the_bring_up() {
    let path = std::env::temp_dir().join(format!("pam-capture-{}.pcap", std::process::id()));
    smol::block_on(async {
        let bus = VirtualBus::with_options(1, Clock::frames(), Some(&path)).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let _: u32 = sd.sdo_read(0x1018, 2).await.expect("sdo");
        let group = group.into_op(md).await.expect("op");
        group.tx_rx(md).await.expect("cycle");
        drop(group);
        drop(bus); // stops the link thread, which flushes the file
    });
    let bytes = std::fs::read(&path).expect("capture file");
    let records = read_all(&bytes).expect("well-formed pcap");
    let _ = std::fs::remove_file(&path);
    assert!(records.len() > 100, "only {} frames", records.len());
    assert_eq!(records.len() % 2, 0, "each request has its reply");
    for pair in records.chunks(2) {
        let (req, rep) = (&pair[0].data, &pair[1].data);
        assert_eq!(&req[12..14], &[0x88, 0xA4], "EtherCAT EtherType");
        assert_eq!(req[6] & 0x02, 0, "request from the master");
        assert_eq!(rep[6] & 0x02, 0x02, "reply marked by the slave");
        assert_eq!(req.len(), rep.len());
    }
    // A CoE SDO response (mailbox type 3, service 3) travels in some reply.
    let coe_reply = records
        .iter()
        .skip(1)
        .step_by(2)
        .any(|r| r.data.windows(2).any(|w| w == [0x00, 0x30]) && r.data.len() > 16 + 12 + 6);
    assert!(coe_reply, "a CoE SDO response is in the capture");
}

#[test]
fn capture_decodes_with_tshark_where_installed() {
    if Command::new("tshark").arg("--version").output().is_err() {
        return crate::common::skip(
            "tshark is not installed; the pcap structure is checked by the other capture test",
        );
    }
    let path = std::env::temp_dir().join(format!("pam-tshark-{}.pcap", std::process::id()));
    smol::block_on(async {
        let bus = VirtualBus::with_options(1, Clock::frames(), Some(&path)).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let _: u32 = sd.sdo_read(0x1018, 2).await.expect("sdo");
        drop(group);
        drop(bus);
    });
    let out = Command::new("tshark")
        .args(["-r"])
        .arg(&path)
        .args([
            "-Y",
            "ecat_mailbox.coe",
            "-T",
            "fields",
            "-e",
            "frame.number",
        ])
        .output()
        .expect("tshark runs");
    let _ = std::fs::remove_file(&path);
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        text.lines().count() >= 2,
        "tshark decodes CoE mailbox frames: {text}"
    );
}

#[test]
fn tshark_decodes_every_sdo_abort_in_a_capture_with_its_code() {
    use master_test::mailbox::{MailboxClient, MailboxGeometry};
    if Command::new("tshark").arg("--version").output().is_err() {
        return crate::common::skip("tshark is not installed");
    }
    let path = std::env::temp_dir().join(format!("pam-aborts-{}.pcap", std::process::id()));
    let provoked = [
        0x0602_0000u32,
        0x0601_0002,
        0x0609_0031,
        0x0601_0000,
        0x0609_0011,
    ];
    smol::block_on(async {
        let bus = VirtualBus::with_options(1, Clock::frames(), Some(&path)).expect("bus");
        let md = &*bus.maindevice;
        let group = bus.init().await.expect("init");
        let sd = group.subdevice(md, 0).expect("slave");
        let mut c = MailboxClient::new(md, sd.configured_address(), MailboxGeometry::standard());
        let got = [
            c.sdo_upload(0x1234, 0, false).await.err(),
            c.sdo_download(0x1018, 1, false, &[1, 0, 0, 0]).await.err(),
            c.sdo_download(0x800D, 2, false, &5000u16.to_le_bytes())
                .await
                .err(),
            c.sdo_upload(0x6000, 2, false).await.err(),
            c.sdo_upload(0x1008, 7, false).await.err(),
        ];
        let codes: Vec<Option<u32>> = got.iter().map(|e| e.as_ref()?.abort_code()).collect();
        assert_eq!(codes, provoked.map(Some), "our client saw the aborts");
        drop(group);
        drop(bus);
    });
    let out = Command::new("tshark")
        .arg("-r")
        .arg(&path)
        .args([
            "-Y",
            "ecat_mailbox.coe.abortcode",
            "-T",
            "fields",
            "-e",
            "ecat_mailbox.coe.abortcode",
        ])
        .output()
        .expect("tshark runs");
    let _ = std::fs::remove_file(&path);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let decoded: Vec<u32> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| u32::from_str_radix(l.trim().trim_start_matches("0x"), 16).ok())
        .collect();
    // Each abort appears once in the reply frame the master read (the
    // frames that polled the mailbox before it was full carry none).
    let mut unique = decoded.clone();
    unique.dedup();
    assert_eq!(unique, provoked, "tshark decoded {decoded:#010x?}");
}
