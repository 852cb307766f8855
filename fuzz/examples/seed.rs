//! Writes the seed corpora into `fuzz/seeds/<target>/` (committed; the
//! fuzzer's own finds go to the ignored `fuzz/corpus/<target>/`).
//!
//! ```text
//! cd fuzz && cargo run --example seed
//! ```
//!
//! - `line_frames`, `mailbox`: frames of real ethercrab sessions on the
//!   virtual bus (master-test's `VirtualBus`, captured to pcap and read
//!   back with `ecat_sim::pcap::read_all`): bring-up to OP of 1
//!   and 3 PAMs, SDO uploads/downloads (expedited, segmented, complete
//!   access), SDO Information, FoE read of `info.txt`, BOOT and an FoE
//!   firmware download. The master's frames become `line_frames` inputs;
//!   the mailbox messages it wrote into SM0 become `mailbox` inputs.
//! - `sii`: the PAM's and the IO8's generated SII images, the PAM's as
//!   Intel HEX, and the vendor dumps of `tests/data/sii-dumps`.
//! - `esi`: the generated ESIs (the PAM's without its 155 KB dictionary
//!   and with a dictionary of one object, the IO8's whole). The ETG schema
//!   files of `shared/esi-schema` are not copied into the repository.
//! - `pam_invariants`: the named master sessions of
//!   `pam_199_p_etc::invariants::seeds` (bring-up, frames stopping,
//!   independent mode, updates cut and rolled back, the vendor password,
//!   cut saves, PDI faults, the watchdog disabled, complete access,
//!   power-stage faults, unreadable boot records), encoded with
//!   `invariants::encode`. `cargo run --example seed -- pam_invariants`
//!   writes only these (no ethercrab sessions).
//! - `efw`: `.efw` images packed with the library (`master-test firmware
//!   pack` does the same), one with a header extension, one for another
//!   product, and a boot state record.

use std::path::{Path, PathBuf};
use std::time::Duration;

use ecat_fuzz::records::push;
use ecat_slave::firmware::{BootState, EFW_HEADER_LEN, EfwHeaderRepr, FirmwareVersion, pack};
use ecat_sim::pcap::read_all;
use ecat_slave::wire::ecat::{Command, Datagram, EcatFrame};
use ecat_slave::wire::ethernet::EthernetFrame;
use master_test::VirtualBus;
use master_test::link::Clock;
use master_test::mailbox::{MailboxClient, MailboxGeometry};

type Error = Box<dyn std::error::Error>;

fn write(dir: &Path, name: &str, bytes: &[u8]) -> Result<(), Error> {
    std::fs::create_dir_all(dir)?;
    std::fs::write(dir.join(name), bytes)?;
    println!("{:>7} bytes  {}", bytes.len(), dir.join(name).display());
    Ok(())
}

/// The master's frames of a capture (replies carry the forwarded bit).
fn requests(pcap: &Path) -> Result<Vec<Vec<u8>>, Error> {
    let bytes = std::fs::read(pcap)?;
    let _ = std::fs::remove_file(pcap);
    Ok(read_all(&bytes)?
        .into_iter()
        .map(|r| r.data)
        .filter(|d| d.get(6).is_some_and(|b| b & 0x02 == 0))
        .collect())
}

/// The mailbox messages the master wrote with FPWR at `sm0` (cut to the
/// header's length).
fn mailbox_writes(frames: &[Vec<u8>], sm0: u16) -> Vec<Vec<u8>> {
    let mut out = vec![];
    for f in frames {
        let Ok(eth) = EthernetFrame::new_checked(&f[..]) else {
            continue;
        };
        let Ok(ecat) = EcatFrame::new_checked(eth.payload()) else {
            continue;
        };
        for r in ecat.datagrams() {
            let Ok(r) = r else { break };
            let Ok(dg) = Datagram::new_checked(&ecat.payload()[r]) else {
                break;
            };
            if dg.command() == Command::Fpwr && dg.ado() == sm0 && dg.data().len() >= 6 {
                let d = dg.data();
                let len = usize::from(u16::from_le_bytes([d[0], d[1]])) + 6;
                out.push(d[..len.min(d.len())].to_vec());
            }
        }
    }
    out
}

/// A `line_frames` input: header byte, then the frames as raw records.
fn frames_input(header: u8, frames: &[Vec<u8>]) -> Vec<u8> {
    let mut v = vec![header];
    for f in frames {
        push(&mut v, 0, f);
    }
    v
}

/// A `mailbox` input: state byte, then each message and a reply read.
fn mailbox_input(state: u8, msgs: &[Vec<u8>]) -> Vec<u8> {
    let mut v = vec![state];
    for m in msgs {
        push(&mut v, 0, m);
        push(&mut v, 2, &[]);
        push(&mut v, 2, &[]);
    }
    v
}

/// Session 1: one PAM, bring-up, SDO traffic, OP with process data.
async fn session_op(n: usize, pcap: &Path) -> Result<(), Error> {
    let bus = VirtualBus::with_options(n, Clock::real(), Some(pcap))?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    let sd = group.subdevice(md, 0)?;
    let _: u32 = sd.sdo_read(0x1018, 2).await?;
    let _: u32 = sd.sdo_read(0x1000, 0).await?;
    let group = master_test::into_op_cyclic(group, md, Duration::from_millis(2)).await?;
    for _ in 0..5 {
        group.tx_rx(md).await?;
    }
    drop(group);
    drop(bus);
    Ok(())
}

/// Session 2: one PAM in PRE-OP, mailbox traffic of every kind, then BOOT
/// and an FoE download.
async fn session_mailbox(pcap: &Path) -> Result<(), Error> {
    use master_test::sdo_info::{entry_description, object_description, od_list};
    let bus = VirtualBus::with_options(1, Clock::real(), Some(pcap))?;
    let md = &*bus.maindevice;
    let group = bus.init().await?;
    let station = group.subdevice(md, 0)?.configured_address();
    let mut c = MailboxClient::new(md, station, MailboxGeometry::standard());
    c.sdo_upload(0x1000, 0, false).await?;
    c.sdo_upload(0x1008, 0, false).await?; // device name: normal/segmented
    c.sdo_upload(0x1018, 0, true).await?; // complete access
    c.sdo_upload(0x1C12, 0, true).await?;
    let _ = c.sdo_upload(0x1234, 0, false).await; // abort
    let _ = c.sdo_download(0x1018, 1, false, &[1, 0, 0, 0]).await; // read only
    let _ = c.sdo_download(0x1C12, 0, true, &[1, 0, 0x16]).await;
    let _ = c
        .sdo_download_with(0x1008, 0, false, b"a long device name!", true)
        .await;
    od_list(&mut c, 1).await?;
    object_description(&mut c, 0x1018).await?;
    entry_description(&mut c, 0x1018, 1, 0x10).await?;
    let _ = master_test::foe::read(&mut c, "info.txt", 0).await;
    master_test::foe::enter_boot(md, station).await?;
    let mut b = MailboxClient::new(md, station, MailboxGeometry::bootstrap());
    let img = master_test::foe::pam_image("11", 2500);
    master_test::foe::write(&mut b, "pam-199-p-etc.efw", 0, &img, |_, _| {}).await?;
    let _ = master_test::foe::read(&mut b, "info.txt", 0).await;
    drop(group);
    drop(bus);
    Ok(())
}

fn main() -> Result<(), Error> {
    let fuzz = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let seeds = fuzz.join("seeds");
    let only: Vec<String> = std::env::args().skip(1).collect();

    // --- pam_invariants: named master sessions ---------------------------
    if only.is_empty() || only.iter().any(|t| t == "pam_invariants") {
        let dir = seeds.join("pam_invariants");
        for (name, actions) in pam_199_p_etc::invariants::seeds() {
            write(&dir, name, &pam_199_p_etc::invariants::encode(&actions))?;
        }
    }
    if !only.is_empty() && only.iter().all(|t| t == "pam_invariants") {
        return Ok(());
    }
    let tmp = std::env::temp_dir().join(format!("ecat-fuzz-seed-{}", std::process::id()));
    std::fs::create_dir_all(&tmp)?;

    // --- line_frames and mailbox, from captures of ethercrab sessions ----
    let dir = seeds.join("line_frames");
    let op1 = tmp.join("op1.pcap");
    smol::block_on(session_op(1, &op1))?;
    let op1 = requests(&op1)?;
    let op3 = tmp.join("op3.pcap");
    smol::block_on(session_op(3, &op3))?;
    let op3 = requests(&op3)?;
    let mbx = tmp.join("mbx.pcap");
    smol::block_on(session_mailbox(&mbx))?;
    let mbx = requests(&mbx)?;
    println!(
        "captured {} + {} + {} master frames",
        op1.len(),
        op3.len(),
        mbx.len()
    );
    // Header: bit 0 three slaves, bits 1-2 start state, bit 3 differential.
    let chunk = 40;
    for (name, header, frames) in [("op1", 0x00u8, &op1), ("op3", 0x01, &op3)] {
        let n = frames.len();
        write(
            &dir,
            &format!("{name}-bring-up"),
            &frames_input(header, &frames[..chunk.min(n)]),
        )?;
        let mid = (n / 2).saturating_sub(chunk / 2);
        write(
            &dir,
            &format!("{name}-middle"),
            &frames_input(header, &frames[mid..(mid + chunk).min(n)]),
        )?;
        write(
            &dir,
            &format!("{name}-op"),
            &frames_input(header, &frames[n.saturating_sub(chunk)..]),
        )?;
    }
    write(
        &dir,
        "op3-bring-up-differential",
        &frames_input(0x09, &op3[..chunk.min(op3.len())]),
    )?;
    // The mailbox session's frames on a line already in PRE-OP (header 0x04).
    let n = mbx.len();
    for (k, start) in [n / 4, n / 2, 3 * n / 4].into_iter().enumerate() {
        let end = (start + chunk).min(n);
        write(
            &dir,
            &format!("mailbox-session-{k}"),
            &frames_input(0x04, &mbx[start..end]),
        )?;
    }
    // Structured frames and the other record kinds.
    let mut v = vec![0x06];
    push(&mut v, 2, &[7, 0x10, 0, 2, 0x20, 2, 0, 0x30, 2, 0x20, 1, 0]);
    push(&mut v, 3, &[5]);
    push(&mut v, 1, &[0; 40]);
    push(&mut v, 4, &[0]);
    push(&mut v, 4, &[1]);
    write(&dir, "structured", &v)?;

    let dir = seeds.join("mailbox");
    let std_msgs = mailbox_writes(&mbx, 0x1000);
    let boot_at = std_msgs
        .iter()
        .position(|m| m.get(5).is_some_and(|b| b & 0x0F == 4) && m.get(6) == Some(&2))
        .unwrap_or(std_msgs.len());
    let (coe, foe) = std_msgs.split_at(boot_at);
    println!(
        "{} mailbox messages ({} before the FoE download)",
        std_msgs.len(),
        coe.len()
    );
    for (state, name) in [(0u8, "preop"), (1, "safeop"), (2, "op")] {
        write(&dir, &format!("sdo-{name}"), &mailbox_input(state, coe))?;
    }
    write(&dir, "foe-boot", &mailbox_input(3, foe))?;
    let mut v = vec![0u8];
    push(&mut v, 1, &[0; 24]);
    push(&mut v, 2, &[]);
    push(&mut v, 3, &[3]);
    push(&mut v, 4, &[0x80, 0, 1, 2, 3]);
    push(&mut v, 5, &[]);
    push(&mut v, 6, &[4, 0]);
    write(&dir, "record-kinds", &v)?;

    // --- sii ---------------------------------------------------------------
    let dir = seeds.join("sii");
    let pam = ecat_esi::sii_image(&pam_199_p_etc::DEVICE);
    write(&dir, "pam.bin", &pam)?;
    let io8 = device_catalog::find("io8")?;
    write(&dir, "io8.bin", &ecat_esi::sii_image(io8.description))?;
    // Intel HEX of the used part of the PAM's image (the rest reads 0xFF).
    let used = pam.iter().rposition(|b| *b != 0xFF).map_or(0, |i| i + 1);
    write(
        &dir,
        "pam-used.hex",
        ecat_esi::ihex::encode(&pam[..used]).as_bytes(),
    )?;
    let dumps = fuzz.join("../tests/data/sii-dumps");
    let mut names: Vec<_> = std::fs::read_dir(&dumps)?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .collect();
    names.sort();
    for p in names {
        if p.extension().is_some_and(|x| x == "bin") {
            let name = p
                .file_name()
                .expect("file name")
                .to_string_lossy()
                .into_owned();
            write(&dir, &format!("dump-{name}"), &std::fs::read(&p)?)?;
        }
    }

    // --- esi (first byte 0: strict UTF-8) ---------------------------------
    let dir = seeds.join("esi");
    let with_mode = |text: &[u8]| [&[0u8][..], text].concat();
    let xml = String::from_utf8(ecat_esi::generate(&pam_199_p_etc::DEVICE)?)?;
    let (a, b) = (
        xml.find("<Profile").ok_or("Profile")?,
        xml.find("</Profile>").ok_or("/Profile")?,
    );
    let short = format!("{}{}", &xml[..a], &xml[b + "</Profile>".len()..]);
    write(&dir, "pam-no-profile.xml", &with_mode(short.as_bytes()))?;
    // A Profile cut to its unit types, the first data types and the first
    // object, to keep the dictionary's shape in the corpus.
    let profile = &xml[a..b + "</Profile>".len()];
    let keep = |text: &str, open: &str, close: &str, item_end: &str, n: usize| -> Option<String> {
        let start = text.find(open)? + open.len();
        let end = text.find(close)?;
        let mut cut = start;
        for _ in 0..n {
            cut += text[cut..end].find(item_end)? + item_end.len();
        }
        Some(format!("{}{}", &text[..cut], &text[end..]))
    };
    let profile =
        keep(profile, "<DataTypes>", "</DataTypes>", "</DataType>", 3).ok_or("DataTypes")?;
    let profile = keep(&profile, "<Objects>", "</Objects>", "</Object>", 1).ok_or("Objects")?;
    let with_profile = format!("{}{}{}", &xml[..a], profile, &xml[b + "</Profile>".len()..]);
    write(
        &dir,
        "pam-one-object.xml",
        &with_mode(with_profile.as_bytes()),
    )?;
    write(
        &dir,
        "io8.xml",
        &with_mode(&ecat_esi::generate(io8.description)?),
    )?;

    // --- efw (first byte: validator chunk size selector) -------------------
    let dir = seeds.join("efw");
    let img = master_test::foe::pam_image("11", 300);
    write(&dir, "pam-300.efw", &[&[0u8][..], &img].concat())?;
    write(&dir, "pam-300-chunks.efw", &[&[0x47u8][..], &img].concat())?;
    let payload: Vec<u8> = (0..100u8).collect();
    let header = EfwHeaderRepr {
        header_len: EFW_HEADER_LEN as u16 + 8,
        flags: 0,
        vendor_id: pam_199_p_etc::VENDOR_ID,
        product_code: pam_199_p_etc::PRODUCT_CODE,
        revision_min: 7,
        revision_max: 7,
        version: FirmwareVersion::new("1.2.3").ok_or("version")?,
        payload_len: 0,
        payload_crc: 0,
    };
    let mut out = vec![0u8; 1024];
    let n = pack(&header, &payload, &mut out)?;
    write(&dir, "pam-extension.efw", &[&[3u8][..], &out[..n]].concat())?;
    let other = master_test::foe::efw_image(
        io8.description.identity.vendor_id,
        io8.description.identity.product_code,
        "2",
        &payload,
    );
    write(&dir, "io8.efw", &[&[1u8][..], &other].concat())?;
    let state = BootState::initial().encode();
    write(&dir, "boot-state", &[&[0u8][..], &state, &state].concat())?;

    let _ = std::fs::remove_dir_all(&tmp);
    Ok(())
}
