//! Integration tests live in `it/`; this crate has no library code.
//!
//! Under `cfg(doctest)` it holds the Rust blocks of the README and of the
//! book's chapters (`docs/book/src`) as doctests, so `cargo test
//! --workspace` compiles and runs every one of them against today's API.

/// The README's Rust blocks (the device for embedded teams).
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct Readme;

/// Book: "Write your own device" (a description and an application).
#[cfg(doctest)]
#[doc = include_str!("../../docs/book/src/write-your-own-device.md")]
pub struct WriteYourOwnDevice;

/// Book: "The commissioning tool" (the mailbox and SDO Information clients).
#[cfg(doctest)]
#[doc = include_str!("../../docs/book/src/commissioning.md")]
pub struct CommissioningTool;

/// Book: "Distributed Clocks" (a line of drifting clocks on the virtual bus).
#[cfg(doctest)]
#[doc = include_str!("../../docs/book/src/distributed-clocks.md")]
pub struct DistributedClocks;

/// Book: "Real ESC chips: the SPI drivers" (the firmware loop on a driver).
#[cfg(doctest)]
#[doc = include_str!("../../docs/book/src/spi-drivers.md")]
pub struct SpiDrivers;

/// Book: "CiA 402 drives" (the twin hook on a twin of servo402's ESI).
#[cfg(doctest)]
#[doc = include_str!("../../docs/book/src/cia402.md")]
pub struct Cia402Drives;
