//! The telegram limits the manuals give (word count, CNT, module
//! addresses): a leaf the codec (`request`, `response`) and the node's
//! rules (`semantics`) share.

use core::ops::RangeInclusive;

/// Most parameter words one CMD 3 reads: 8 (Profibus manual 3.1, "N-low …
/// 1 to 8 (0x08) (maximal 8 parameters readable at once)"; 4.1.3 exception
/// 3, "CNT == 0 or CNT > 16").
pub const MAX_READ_WORDS: u16 = 8;

/// Most data bytes in a CMD 3 response: CNT = 2·N ≤ 16 (Profibus manual
/// 3.2, "Maximal 16 data bytes"; 4.1.3 exception 3).
pub const MAX_READ_CNT: u8 = 16;

/// Modules a CMD 15 reaches: SNUM and the SADR of a CMD 15 response are
/// 1..=5 (3.4: "all slaves (modules) at a given node with the SADR from 1
/// to 5 can be reached"; 5.1 "SNUM … (Maximum 5)"; 5.2 "1 to max 5").
pub const MODULE_ADDRESSES: RangeInclusive<u8> = 1..=5;

/// Module addresses CMD 3 and CMD 6 reach: 1..=32 (3.4: "SADR also could be
/// set to any value between 1 and 32"; parameter E22, ID 0xA3, range 0..32
/// with 0 = no bus function). Not enforced by the codec: the node answers
/// an absent module with exception 5.
pub const SADR_RANGE: RangeInclusive<u8> = 1..=32;
