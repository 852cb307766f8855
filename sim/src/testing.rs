//! The core's test device ([`ecat_slave::testing`]) on the software ESC,
//! for this crate's unit tests.

use crate::chain::Chain;
use crate::slave::SoftSlave;
pub use ecat_slave::testing::TestApp;

/// A test-device slave on the software ESC.
pub fn slave() -> SoftSlave<TestApp> {
    SoftSlave::new(TestApp::default())
}

/// A line of `n` test devices.
pub fn line(n: usize) -> Chain {
    Chain::of(n, TestApp::default)
}
