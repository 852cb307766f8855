//! The PAM's safety rules as invariants over random master sessions
//! (docs/SAFETY.md, "Invariants"): the input decodes into master actions
//! (`pam_199_p_etc::invariants::decode`: state requests with and without
//! SM2/SM3, cyclic frames stopping and resuming, SDO downloads of any
//! object with and without complete access, time jumps, power cycles, cut
//! saves, PDI faults, a stalled firmware, FoE downloads cut anywhere,
//! unreadable boot records, EEPROM and flash corruption), which the
//! harness plays against a software PAM through EtherCAT frames.
//!
//! Invariants: no panic, and I1..I6 hold after every firmware pass (the
//! harness reports the first broken one with the action that broke it).
//! The same actions drive the property test
//! `devices/pam-199-p-etc/src/tests/invariants.rs`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pam_199_p_etc::invariants::{Harness, decode};

fuzz_target!(|data: &[u8]| {
    let actions = decode(data);
    let mut h = Harness::new();
    if let Err(v) = h.run(&actions) {
        let upto = v.step.min(actions.len().saturating_sub(1));
        panic!("{v}\nactions: {:#?}", &actions[..=upto]);
    }
});
