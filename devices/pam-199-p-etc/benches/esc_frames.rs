//! The frames of the software ESC benchmarks (`benches/esc.rs`) and of the
//! instruction count (`examples/cycle_count.rs`): a line of PAM slaves
//! configured as ethercrab configures it, and one process-data cycle as
//! its `tx_rx` sends it.

use ecat_sim::chain::Chain;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::Command;

/// Output bytes of a PAM slave's image.
pub const OUT: u16 = 5;
/// Input bytes of a PAM slave's image.
pub const IN: u16 = 14;

/// One FMMU of a configuration frame: logical start and length, first and
/// last bit (0 and 7 for whole bytes).
pub struct Window {
    /// Logical start address.
    pub logical: u32,
    /// Length in bytes.
    pub len: u16,
    /// First bit of the first byte.
    pub start_bit: u8,
    /// Last bit of the last byte.
    pub stop_bit: u8,
}

/// The frame that configures slave `i`: station address `0x1000 + i`, SM2
/// (0x1100, `sm_out` bytes) and SM3 (0x1180, `sm_in` bytes), FMMU0 writing
/// `out` into SM2 and FMMU1 reading `inp` from SM3 (both at physical bit 0).
pub fn slave_config_frame(
    i: u16,
    (sm_out, sm_in): (u16, u16),
    out: Window,
    inp: Window,
) -> Vec<u8> {
    let mut buf = vec![0u8; 512];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
    let station = 0x1000 + i;
    let adp = 0u16.wrapping_sub(i) as u32;
    b.push(Command::Apwr, adp | (0x0010 << 16), &station.to_le_bytes())
        .expect("fits");
    let [ol, oh] = sm_out.to_le_bytes();
    let [il, ih] = sm_in.to_le_bytes();
    let sm2 = [0x00, 0x11, ol, oh, 0x64, 0, 1, 0];
    let sm3 = [0x80, 0x11, il, ih, 0x20, 0, 1, 0];
    b.push(Command::Apwr, adp | (0x0810 << 16), &sm2)
        .expect("fits");
    b.push(Command::Apwr, adp | (0x0818 << 16), &sm3)
        .expect("fits");
    let fmmu = |w: &Window, physical: u16, kind: u8| {
        let mut f = [0u8; 16];
        f[0..4].copy_from_slice(&w.logical.to_le_bytes());
        f[4..6].copy_from_slice(&w.len.to_le_bytes());
        f[6] = w.start_bit;
        f[7] = w.stop_bit;
        f[8..10].copy_from_slice(&physical.to_le_bytes());
        f[11] = kind; // 2 = write, 1 = read
        f[12] = 1; // active
        f
    };
    b.push(Command::Apwr, adp | (0x0600 << 16), &fmmu(&out, 0x1100, 2))
        .expect("fits");
    b.push(Command::Apwr, adp | (0x0610 << 16), &fmmu(&inp, 0x1180, 1))
        .expect("fits");
    let len = b.finish();
    buf.truncate(len);
    buf
}

/// The frames that configure slave `i` of a line as ethercrab does:
/// station address, SM2/SM3 and FMMU0/1 (each slave's 5 output bytes then
/// 14 input bytes, back to back).
pub fn config_frames(n: usize) -> Vec<Vec<u8>> {
    (0..n as u16)
        .map(|i| {
            let log_out = u32::from(i) * u32::from(OUT + IN);
            let whole = |logical, len| Window {
                logical,
                len,
                start_bit: 0,
                stop_bit: 7,
            };
            slave_config_frame(
                i,
                (OUT, IN),
                whole(log_out, OUT),
                whole(log_out + u32::from(OUT), IN),
            )
        })
        .collect()
}

/// Largest EtherCAT payload in a standard Ethernet frame.
const MAX_PAYLOAD: usize = 1498;

/// Bytes a datagram adds to its data: 10 header + 2 working counter.
const DATAGRAM_OVERHEAD: usize = 12;

/// Builds one frame from datagrams (command, address, data).
pub fn build(datagrams: &[(Command, u32, Vec<u8>)]) -> Vec<u8> {
    let mut buf = vec![0u8; 1600];
    let mut b = FrameBuilder::new(&mut buf, [0x10; 6]).expect("buffer");
    for (cmd, addr, data) in datagrams {
        b.push(*cmd, *addr, data).expect("fits");
    }
    let len = b.finish();
    buf.truncate(len);
    buf
}

/// The frames of one cycle as ethercrab's `tx_rx` sends them: LRWs over
/// the whole image (split over as many frames as it needs), then FPRD
/// 0x0130 (AL status) of every slave in the room left and further
/// frames. Returns the frames and the working counter they must collect:
/// per LRW, 2 for every slave whose outputs it touches and 1 for every
/// slave whose inputs it touches (a slave straddling two LRWs counts in
/// both); 1 per FPRD.
pub fn cycle_frames(n: usize) -> (Vec<Vec<u8>>, u32) {
    let slot = usize::from(OUT + IN);
    let image = n * slot;
    let mut frames = Vec::new();
    let mut current: Vec<(Command, u32, Vec<u8>)> = Vec::new();
    let mut used = 0;
    let mut wkc = 0u32;
    let mut off = 0;
    while off < image {
        let room = MAX_PAYLOAD.saturating_sub(used + DATAGRAM_OVERHEAD);
        if room < 64 {
            frames.push(build(&current));
            current.clear();
            used = 0;
            continue;
        }
        let len = room.min(image - off);
        for i in 0..n {
            let out = i * slot..i * slot + usize::from(OUT);
            let inp = out.end..(i + 1) * slot;
            wkc += 2 * u32::from(out.start < off + len && off < out.end);
            wkc += u32::from(inp.start < off + len && off < inp.end);
        }
        current.push((Command::Lrw, off as u32, vec![0x5A; len]));
        used += DATAGRAM_OVERHEAD + len;
        off += len;
    }
    for i in 0..n as u32 {
        if used + DATAGRAM_OVERHEAD + 2 > MAX_PAYLOAD {
            frames.push(build(&current));
            current.clear();
            used = 0;
        }
        current.push((Command::Fprd, (0x1000 + i) | (0x0130 << 16), vec![0, 0]));
        used += DATAGRAM_OVERHEAD + 2;
        wkc += 1;
    }
    frames.push(build(&current));
    (frames, wkc)
}

/// Sum of the working counters in a processed frame.
pub fn wkc_sum(frame: &[u8]) -> u32 {
    let eth = ecat_slave::wire::ethernet::EthernetFrame::new_checked(frame).expect("eth");
    let ecat = ecat_slave::wire::ecat::EcatFrame::new_checked(eth.payload()).expect("ecat");
    ecat.datagrams()
        .map(|r| {
            let r = r.expect("datagram");
            let dg = ecat_slave::wire::ecat::Datagram::new_checked(&ecat.payload()[r]).expect("dg");
            u32::from(dg.wkc())
        })
        .sum()
}

/// Configures a `Chain` (the virtual link's line) with the same frames.
pub fn configure_chain(chain: &mut Chain, n: usize) {
    for mut f in config_frames(n) {
        chain.process_frame(&mut f);
    }
}
