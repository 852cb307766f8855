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
