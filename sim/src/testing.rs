//! The core's test device ([`ecat_slave::testing`]) on the software ESC,
//! for this crate's unit tests.

use crate::chain::Chain;
use crate::slave::SoftSlave;
pub use ecat_slave::testing::TestApp;
use ecat_slave::wire::builder::FrameBuilder;
use ecat_slave::wire::ecat::Command;

/// A test-device slave on the software ESC.
pub fn slave() -> SoftSlave<TestApp> {
    SoftSlave::new(TestApp::default())
}

/// A line of `n` test devices.
pub fn line(n: usize) -> Chain {
    Chain::of(n, TestApp::default)
}

/// An Ethernet frame (source 10:10:10:10:10:10) with one datagram.
pub fn one_datagram(cmd: Command, address: u32, data: &[u8]) -> Vec<u8> {
    let mut buf = vec![0u8; 200];
    let mut fb = FrameBuilder::new(&mut buf, [0x10; 6]).unwrap();
    fb.push(cmd, address, data).unwrap();
    let len = fb.finish();
    buf.truncate(len);
    buf
}

/// FMMU registers: `len` bytes at `logical` to `physical`, reading
/// (`kind` 1) or writing (2), bit 0 to 7.
pub fn fmmu(logical: u32, len: u16, physical: u16, kind: u8) -> Vec<u8> {
    let mut f = vec![0u8; 16];
    f[0..4].copy_from_slice(&logical.to_le_bytes());
    f[4..6].copy_from_slice(&len.to_le_bytes());
    f[7] = 7;
    f[8..10].copy_from_slice(&physical.to_le_bytes());
    f[11] = kind;
    f[12] = 1;
    f
}

/// SyncManager registers: `len` bytes at `start`, `control`, enabled.
pub fn sm(start: u16, len: u16, control: u8) -> Vec<u8> {
    let mut s = vec![0u8; 8];
    s[0..2].copy_from_slice(&start.to_le_bytes());
    s[2..4].copy_from_slice(&len.to_le_bytes());
    s[4] = control;
    s[6] = 1;
    s
}
