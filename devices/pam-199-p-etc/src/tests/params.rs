//! Parameter storage (core) with the PAM's parameter set.

use crate::description::od::DICT;
use ecat_slave::hal::MemNv;
use ecat_slave::params::*;

/// Flat positions of the stored entries (what the core's private
/// `stored_entries` walks).
fn stored_entries() -> Vec<(usize, &'static ecat_slave::od::Entry)> {
    DICT.entries()
        .filter(|(_, _, e)| {
            e.backup() && !e.gap() && e.data_type != ecat_slave::od::DataType::VisibleString
        })
        .map(|(f, _, e)| (f, e))
        .collect()
}

fn changed() -> crate::Store {
    let mut s = crate::store();
    s.set(0x800D, 2, 2750);
    s.set(0x8006, 1, -7777);
    s.set(0x8002, 2, 120_000);
    s.set(0xF800, 1, 16383);
    s.set(0xF800, 2, 2);
    s
}

#[test]
fn parameter_set_fits_a_slot() {
    assert!(
        HEADER + payload_len(&DICT) <= SLOT_SIZE,
        "{}",
        payload_len(&DICT)
    );
    assert!(payload_len(&DICT) > 200);
}

#[test]
fn save_then_load_restores_every_stored_value() {
    let mut nv = MemNv::<STORAGE_SIZE>::new();
    assert_eq!(stored(&nv, &DICT), Stored::Blank);
    let a = changed();
    assert_eq!(save(&a, &mut nv), Ok(1));
    let mut b = crate::store();
    assert_eq!(load(&mut b, &nv), Ok(1));
    for (flat, _) in stored_entries() {
        assert_eq!(a.value(flat), b.value(flat), "flat {flat}");
    }
    assert_eq!(b.get(0x8006, 1), Some(-7777));
}

#[test]
fn saves_alternate_slots_and_the_newest_wins() {
    let mut nv = MemNv::<STORAGE_SIZE>::new();
    let mut s = crate::store();
    for i in 0..5 {
        s.set(0x800D, 2, 1000 + i);
        assert_eq!(save(&s, &mut nv), Ok(i as u32 + 1));
    }
    let mut t = crate::store();
    load(&mut t, &nv).unwrap();
    assert_eq!(t.get(0x800D, 2), Some(1004));
}

#[test]
fn a_power_cut_at_every_byte_of_a_save_leaves_a_valid_set() {
    let old = crate::store();
    let new = changed();
    let mut base = MemNv::<STORAGE_SIZE>::new();
    save(&old, &mut base).unwrap();
    save(&old, &mut base).unwrap();
    let total = HEADER + payload_len(&DICT);
    for cut in 0..=total {
        let mut nv = base.clone();
        nv.cut_power_after(cut);
        let res = save(&new, &mut nv);
        nv.restore_power();
        let mut s = crate::store();
        s.set(0x800D, 2, 9);
        let seq = load(&mut s, &nv).expect("a valid set after the cut");
        assert_eq!(res.is_ok(), cut == total, "cut {cut}");
        // Either the whole new set (the bytes not written already held
        // the new record's tail, or the write completed) or the whole
        // old one; never a mix.
        let expect = match seq {
            3 => &new,
            2 => &old,
            other => panic!("cut {cut}: sequence {other}"),
        };
        if cut < HEADER + 4 {
            assert_eq!(seq, 2, "cut {cut}: the new record cannot be valid yet");
        }
        for (flat, _) in stored_entries() {
            assert_eq!(s.value(flat), expect.value(flat), "cut {cut} flat {flat}");
        }
    }
}

#[test]
fn corrupted_storage_is_reported_not_loaded() {
    let mut nv = MemNv::<STORAGE_SIZE>::new();
    save(&changed(), &mut nv).unwrap();
    nv.bytes_mut()[HEADER + 3] ^= 0x40;
    assert_eq!(stored(&nv, &DICT), Stored::Corrupt);
    let mut s = crate::store();
    assert_eq!(load(&mut s, &nv), Err(ParamError::NoValidSet));
    assert_eq!(s.get(0x800D, 2), Some(1000), "nothing applied");
}

#[test]
fn defaults_restore_only_parameters() {
    let mut s = changed();
    s.set(0x7000, 3, 5);
    restore_defaults(&mut s);
    assert_eq!(s.get(0x800D, 2), Some(1000));
    assert_eq!(s.get(0xF800, 2), Some(1));
    assert_eq!(s.get(0x7000, 3), Some(5), "process data untouched");
}

#[test]
fn too_small_storage_is_an_error() {
    let mut nv = MemNv::<100>::new();
    assert_eq!(
        save(&crate::store(), &mut nv),
        Err(ParamError::TooSmall(100))
    );
}
