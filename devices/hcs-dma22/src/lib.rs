//! # hcs-dma22: the HCS DMA-22(A) amplifier node and its telegram
//!
//! The HCS DMA-22(A) digital amplifier node as an EtherCAT *modular
//! device* (ETG.5001) on the `ecat-slave` core: one node with 1..=5
//! DMA-22(A) modules in its slots (module address E22 = slot), each with
//! the parameter list of the manual's chapter 7, its CMD 15 block as
//! process data, a behaviour model, and the telegram channel over CoE.
//! The crate has the IO8 example's layout: [`description`] (what the node
//! is, [`DEVICE`]), [`app`] (what it does, [`Dma22Node`], with its tests); the
//! node is simulated only, so it has no board module (the modules' inputs,
//! hardware enable and digital inputs, are set through
//! [`Dma22Node::module_mut`]).
//!
//! Layers: `app` → `description`, `telegram`
//!
//! The codec ([`telegram`]) reads and writes the HCS fieldbus telegram that
//! the DMA-22(A) node exchanges with its master over EtherNet/IP and
//! Profibus-DP (and that the DAC-42(A) uses over Profinet): CMD 3 (read up
//! to 8 parameter words), CMD 6 (write one parameter), CMD 15 (write the
//! process data of 1..=5 modules, answered by one module at a time) and the
//! error replies 0x83 / 0x86 / 0x8F with their exception codes. It is
//! `#![no_std]`, heap-free and zero-copy in the style of the core's `wire`
//! module: views over any `AsRef<[u8]>` plus `Repr` types with `parse`,
//! `emit` and `buffer_len`.
//!
//! ```
//! use hcs_dma22::telegram::{ReadRequest, RequestRepr, ResponseRepr};
//!
//! // Manual 4.2: the master reads parameter d1.07 (ID 0x0007) of module 1.
//! let request = RequestRepr::parse(&[0x24, 0x01, 0x03, 0x00, 0x07, 0x00, 0x01])?;
//! assert_eq!(
//!     request,
//!     RequestRepr::Read(ReadRequest { tadr: 0x24, sadr: 1, id: 0x0007, words: 1 })
//! );
//!
//! // ... and module 1 answers CNT = 2 bytes, DATA = 0x0133.
//! let response = ResponseRepr::parse(&[0x24, 0x01, 0x03, 0x02, 0x01, 0x33])?;
//! let ResponseRepr::Read(read) = response else { unreachable!() };
//! assert_eq!(read.words(), &[0x0133]);
//!
//! let mut out = [0u8; 6];
//! assert_eq!(response.emit(&mut out)?, 6);
//! assert_eq!(out, [0x24, 0x01, 0x03, 0x02, 0x01, 0x33]);
//! # Ok::<(), hcs_dma22::telegram::TelegramError>(())
//! ```
//!
//! Sources: the HCS manuals "DMA-22(A) EtherNet/IP" (chapters 3.3, 3.4, 4,
//! 5, 6.3), "DMA Profibus" (chapters 1.4, 1.5, 3, 4, 5) and "DAC-42(A)-x-PN"
//! (chapter 9). Section numbers in this crate refer to the EtherNet/IP
//! manual unless said otherwise; `NOTES.md` lists where the manuals are
//! ambiguous or disagree and what the codec decided.
#![cfg_attr(not(test), no_std)]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

pub mod app;
pub mod description;
pub mod telegram;

pub use app::Dma22Node;
pub use description::{
    DEVICE, DEVICE_NAME, MODULE_IDENT, PRODUCT_CODE, REVISION, SLOTS, VENDOR_ID,
};
