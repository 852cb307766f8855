use ecat_sim::SoftSlave;

use ecat_slave::al::AlState;
use ecat_slave::device::Tick;

use super::model::{id, status};
use super::*;
use ecat_slave::od::Od;

fn node3() -> SoftSlave<Dma22Node<3>> {
    SoftSlave::new(Dma22Node::<3>::default())
}

#[test]
fn power_on_detects_the_modules_and_assigns_their_pdos() {
    let s = node3();
    let od = s.slave().od();
    assert_eq!(od.get(0xF050, 0), Some(3));
    assert_eq!(od.get(0xF050, 3), Some(i64::from(MODULE_IDENT)));
    assert_eq!(od.get(0xF050, 4), Some(0));
    assert_eq!(od.get(0x1C12, 0), Some(3));
    assert_eq!(od.get(0x1C12, 3), Some(0x1602));
    assert_eq!(od.get(0x1C13, 0), Some(3));
    assert_eq!(od.get(0x1C13, 1), Some(0x1A00));
    assert_eq!(model::get(od, 2, id::E22), 3, "E22 = module address");
    assert_eq!(model::get(od, 0, id::E00), 3, "mode 3");
    assert_eq!(model::get(od, 0, 0x00), 1001, "Vers 10.01");
    assert_eq!(od.get(0xF030, 0), Some(0), "nothing configured yet");
}

#[test]
fn every_parameter_id_maps_to_its_entry_and_back() {
    let dict = &od::DICT;
    let mut found = 0;
    for pid in 0..=0x109u16 {
        let (index, sub) = od::parameter(0, pid).unwrap();
        if let Some((_, e)) = dict.find_entry(index, sub) {
            found += 1;
            let name = e.name.split(' ').next().unwrap();
            assert!(!name.is_empty(), "ID {pid:#x}");
        }
    }
    assert_eq!(found, 180, "every implemented row of chapter 7");
    assert_eq!(od::parameter(0, 0x10A), None);
    let (i, s) = od::parameter(2, id::A1_01).unwrap();
    assert_eq!((i, s), (0x8020, 0x20));
    assert_eq!(
        dict.find_entry(i, s).unwrap().1.name,
        "A1.01 Ethernet set value (Branch 1)"
    );
}

fn run(
    m: &mut model::Module,
    od: &mut Od,
    slot: u8,
    mode: u8,
    t_ms: u64,
    valid: bool,
) -> Option<u8> {
    m.tick(od, slot, mode, t_ms * 1_000_000, valid)
}

fn outputs(od: &mut Od, slot: u8, control: u8, pv1: i16, pv2: i16) {
    let o = od::slot_index(od::OUTPUTS, slot);
    od.set(o, 1, i64::from(control));
    od.set(o, 2, i64::from(pv1));
    od.set(o, 3, i64::from(pv2));
}

fn inputs(od: &Od, slot: u8) -> (u16, i16, i16) {
    let i = od::slot_index(od::INPUTS, slot);
    (
        od.get(i, 1).unwrap() as u16,
        od.get(i, 2).unwrap() as i16,
        od.get(i, 3).unwrap() as i16,
    )
}

#[test]
fn manual_5_4_2_three_modules_in_mode_3_answer_their_set_values() {
    let mut s = node3();
    let od = s.slave_mut().od_mut();
    let mut ms = [model::Module::new(); 3];
    for (slot, sv) in [(0u8, 1000i16), (1, 2000), (2, -3000)] {
        outputs(od, slot, 0x00, sv, 0);
        run(&mut ms[usize::from(slot)], od, slot, 3, 0, true);
        // VALUE1 = d1.11 = 0, VALUE2 = d1.10 = the set value, HW enable.
        assert_eq!(
            inputs(od, slot),
            (status::HW_ENABLE, 0, sv),
            "module {}",
            slot + 1
        );
        assert_eq!(model::get(od, slot, id::A1_01), i64::from(sv));
    }
}

#[test]
fn bus_disable_drops_the_output_and_shows_in_the_status_word() {
    let mut s = node3();
    let od = s.slave_mut().od_mut();
    let mut m = model::Module::new();
    // Mode 1: value 1 and 2 are the currents A and B.
    outputs(od, 0, 0x00, 5000, 0);
    run(&mut m, od, 0, 1, 0, true);
    let (_, ia, ib) = inputs(od, 0);
    // 50 % of the 2.7 A solenoid (E03 = 6, E10 = 100 %).
    assert_eq!((ia, ib), (1350, 0));
    outputs(od, 0, 0x80, 5000, 0);
    run(&mut m, od, 0, 1, 1, true);
    assert_eq!(
        inputs(od, 0),
        (status::HW_ENABLE | status::BUS_DISABLE, 0, 0)
    );
    outputs(od, 0, 0x00, -5000, 0);
    run(&mut m, od, 0, 1, 2, true);
    assert_eq!(inputs(od, 0), (status::HW_ENABLE, 0, 1350), "solenoid B");
}

#[test]
fn ramps_move_the_desired_value_at_the_configured_rate() {
    let mut s = node3();
    let od = s.slave_mut().od_mut();
    let mut m = model::Module::new();
    // r1.03 (0 -> +) = 100: 1 s for 10 V, 1 V per 100 ms.
    model::set(od, 0, id::R1_01 + 2, 100);
    outputs(od, 0, 0, 5000, 0);
    run(&mut m, od, 0, 3, 0, true);
    assert_eq!(model::get(od, 0, id::D1_10), 0);
    run(&mut m, od, 0, 3, 100, true);
    assert_eq!(model::get(od, 0, id::D1_10), 1000);
    run(&mut m, od, 0, 3, 1000, true);
    assert_eq!(model::get(od, 0, id::D1_10), 5000, "reached, not passed");
}

#[test]
fn timeout_e23_with_e26_0_resumes_and_with_e26_1_needs_an_acknowledge() {
    for e26 in [0, 1] {
        let mut s = node3();
        let od = s.slave_mut().od_mut();
        let mut m = model::Module::new();
        model::set(od, 0, id::E23, 5); // 50 ms
        model::set(od, 0, id::E26, e26);
        outputs(od, 0, 0, 1000, 0);
        assert_eq!(run(&mut m, od, 0, 3, 0, true), None);
        assert_eq!(run(&mut m, od, 0, 3, 40, false), None, "within E23");
        assert_eq!(inputs(od, 0).2, 1000, "set value held within the window");
        assert_eq!(
            run(&mut m, od, 0, 3, 60, false),
            Some(model::error::TIMEOUT)
        );
        let (st, _, v2) = inputs(od, 0);
        assert_eq!(st, status::HW_ENABLE | status::ERROR | 0x0A);
        assert_eq!(v2, 0, "set values discarded");
        outputs(od, 0, 0, 1000, 0);
        run(&mut m, od, 0, 3, 70, true);
        if e26 == 0 {
            assert_eq!(inputs(od, 0), (status::HW_ENABLE, 0, 1000), "resumes");
        } else {
            assert_eq!(inputs(od, 0).0 & status::ERROR, status::ERROR, "latched");
            outputs(od, 0, 0x80, 1000, 0);
            run(&mut m, od, 0, 3, 80, true);
            outputs(od, 0, 0x00, 1000, 0);
            run(&mut m, od, 0, 3, 90, true);
            assert_eq!(inputs(od, 0), (status::HW_ENABLE, 0, 1000), "acknowledged");
            assert_eq!(m.errors, 1);
        }
    }
}

#[test]
fn without_hw_enable_the_control_byte_is_reset_and_nothing_drives() {
    let mut s = node3();
    let od = s.slave_mut().od_mut();
    let mut m = model::Module::new();
    m.hw_enable = false;
    outputs(od, 0, 0x81, 2000, 0);
    run(&mut m, od, 0, 3, 0, true);
    assert_eq!(m.control(), 0);
    assert_eq!(inputs(od, 0), (0, 0, 0));
    assert_eq!(model::get(od, 0, id::D1_07), 0);
}

#[test]
fn a_gap_of_hours_saturates_the_ramp_and_the_integral_instead_of_overflowing() {
    // Closed loop (mode 3, PI controller C1.00 = 1) at the I part's limits.
    let setup = |od: &mut Od, ramp: i64| {
        model::set(od, 0, id::C1_00 + 17, 4000); // C1.17 I portion, maximum
        model::set(od, 0, id::C1_33, 9999); // C1.33 limit 9.999 V
        for k in 0..4 {
            model::set(od, 0, id::R1_01 + k, ramp);
        }
        outputs(od, 0, 0, 5000, 0);
    };
    // A ramp of 1 (10 ms for 10 V) over half of u64's nanoseconds.
    let mut s = node3();
    let od = s.slave_mut().od_mut();
    let mut m = model::Module::new();
    setup(od, 1);
    m.tick(od, 0, 3, 0, true);
    m.tick(od, 0, 3, u64::MAX / 2, true);
    assert_eq!(
        model::get(od, 0, id::D1_10),
        5000,
        "ramp reached, not wrapped"
    );
    assert_eq!(model::get(od, 0, id::D1_13), 9999, "I part at its limit");
    m.tick(od, 0, 3, u64::MAX, true);
    assert_eq!(model::get(od, 0, id::D1_13), 9999);
    // No ramp, two hours between cycles, both signs.
    for (sv, y) in [(5000i16, 9999), (-5000, -9999)] {
        let mut s = node3();
        let od = s.slave_mut().od_mut();
        let mut m = model::Module::new();
        setup(od, 0);
        outputs(od, 0, 0, sv, 0);
        run(&mut m, od, 0, 3, 0, true);
        run(&mut m, od, 0, 3, 2 * 3600 * 1000, true);
        assert_eq!(model::get(od, 0, id::D1_13), y, "set value {sv}");
    }
}

/// One tick of `node`'s application in AL state `state` (outputs valid in
/// OP), as the core runs it.
fn node_tick<const N: usize>(node: &mut Dma22Node<N>, od: &mut Od, state: AlState, t_ms: u64) {
    let mut em = ecat_slave::coe::emergency::Emergencies::default();
    node.tick(&mut Tick::new(
        od,
        t_ms * 1_000_000,
        state == AlState::Op,
        state,
        &mut em,
    ));
}

/// Solenoid currents A and B of module 1 (d1.07, d1.08).
fn currents(od: &Od) -> (i64, i64) {
    (model::get(od, 0, id::D1_07), model::get(od, 0, id::D1_08))
}

#[test]
fn set_values_written_outside_op_leave_the_solenoid_currents_at_0() {
    // Mode 1: the set values are the solenoid currents' (50 % of the
    // 2.7 A solenoid = 1350 mA).
    let mut s = SoftSlave::new(Dma22Node::<1>::new([1]));
    let (node, od) = s.slave_mut().app_and_od();
    // An SDO download of A1.01 = 5.000 V in PRE-OP: stored, not driven.
    let (index, sub) = od::parameter(0, id::A1_01).unwrap();
    assert_eq!(
        od.download(index, sub, &5000i16.to_le_bytes(), AlState::PreOp),
        Ok(5000)
    );
    for t in 0..3 {
        node_tick(node, od, AlState::PreOp, t);
        assert_eq!(currents(od), (0, 0), "PRE-OP, tick {t}");
    }
    assert_eq!(
        model::get(od, 0, id::A1_01),
        5000,
        "the value stays written"
    );
    assert_eq!(model::get(od, 0, id::D1_09), 0);
    // A CMD 15 telegram through the channel (set value 2.5 V), then
    // SAFE-OP: still nothing.
    let mut out = [0u8; crate::description::od::MAX_TELEGRAM];
    let req = [0x40, 0x01, 0x0F, 0x00, 0x09, 0xC4, 0x00, 0x00];
    node.channel.serve(
        od,
        &req,
        channel::Modules {
            modules: &mut node.modules,
            modes: &node.modes,
        },
        &mut out,
    );
    assert_eq!(model::get(od, 0, id::A1_01), 2500);
    node_tick(node, od, AlState::PreOp, 3);
    assert_eq!(currents(od), (0, 0), "telegram in PRE-OP");
    node_tick(node, od, AlState::SafeOp, 4);
    assert_eq!(currents(od), (0, 0), "SAFE-OP");
    // OP with valid cyclic outputs acts as before.
    outputs(od, 0, 0x00, 5000, 0);
    node_tick(node, od, AlState::Op, 5);
    assert_eq!(currents(od), (1350, 0), "OP");
    outputs(od, 0, 0x00, -5000, 0);
    node_tick(node, od, AlState::Op, 6);
    assert_eq!(currents(od), (0, 1350), "OP, solenoid B");
    // Back to SAFE-OP: the power stage goes off at once.
    node_tick(node, od, AlState::SafeOp, 7);
    assert_eq!(currents(od), (0, 0), "left OP");
}

/// Serves one telegram through the channel of a fresh node with `N`/// Serves one telegram through the channel of a fresh node with `N`
/// modules (after one tick, so the modules' inputs are current).
struct Bench<const N: usize> {
    slave: SoftSlave<Dma22Node<N>>,
    channel: channel::Channel,
    modules: [model::Module; N],
}

impl<const N: usize> Bench<N> {
    fn new() -> Self {
        let mut slave = SoftSlave::new(Dma22Node::<N>::default());
        let mut modules = [model::Module::new(); N];
        for (k, m) in modules.iter_mut().enumerate() {
            m.tick(slave.slave_mut().od_mut(), k as u8, 3, 0, false);
        }
        Bench {
            slave,
            channel: channel::Channel::new(),
            modules,
        }
    }

    fn send(&mut self, request: &[u8]) -> Vec<u8> {
        let mut out = [0u8; crate::description::od::MAX_TELEGRAM];
        let modes = [3u8; N];
        let n = self.channel.serve(
            self.slave.slave_mut().od_mut(),
            request,
            channel::Modules {
                modules: &mut self.modules,
                modes: &modes,
            },
            &mut out,
        );
        out[..n].to_vec()
    }

    fn od(&mut self) -> &mut Od {
        self.slave.slave_mut().od_mut()
    }
}

#[test]
fn channel_cmd3_reads_parameters_and_answers_a_changed_request_only() {
    let mut b = Bench::<3>::new();
    // Manual 4.2: read d1.07 (ID 7) of module 1; one word.
    model::set(b.od(), 0, id::D1_07, 0x0133);
    let req = [0x24, 0x01, 0x03, 0x00, 0x07, 0x00, 0x01];
    assert_eq!(b.send(&req), [0x24, 0x01, 0x03, 0x02, 0x01, 0x33]);
    assert_eq!(b.send(&req), [] as [u8; 0], "unchanged: no answer (3.3)");
    let mut again = req;
    again[0] = 0x25;
    assert_eq!(
        b.send(&again)[..4],
        [0x25, 0x01, 0x03, 0x02],
        "TADR changed"
    );
    // Three words from ID 0x2C (C1.03 gain A, C1.04, C1.05): defaults 100.
    let three = b.send(&[0x26, 0x02, 0x03, 0x00, 0x2C, 0x00, 0x03]);
    assert_eq!(three, [0x26, 0x02, 0x03, 0x06, 0, 100, 0, 100, 0, 100]);
    // A reserved ID (S1.08, 0x1A) and a module that is not plugged.
    assert_eq!(
        b.send(&[0x27, 0x01, 0x03, 0x00, 0x1A, 0x00, 0x01]),
        [0x27, 0x01, 0x83, 0x02]
    );
    assert_eq!(
        b.send(&[0x28, 0x04, 0x03, 0x00, 0x07, 0x00, 0x01]),
        [0x28, 0x04, 0x83, 0x05]
    );
}

#[test]
fn channel_cmd6_writes_with_the_parameter_rules() {
    let mut b = Bench::<3>::new();
    // Manual 4.4.2, 4.): set value A2.01 (ID 0x27) = -9.999 V.
    let req = [0x12, 0x01, 0x06, 0x00, 0x27, 0xD8, 0xF1];
    assert_eq!(b.send(&req), req, "CMD 6 answers with the request");
    assert_eq!(model::get(b.od(), 0, id::A2_01), -9999);
    // Read-only d1.07: writing failed (4); C1.00 = 5 > 4: wrong value (3).
    assert_eq!(
        b.send(&[0x13, 0x01, 0x06, 0x00, 0x07, 0x00, 0x01]),
        [0x13, 0x01, 0x86, 0x04]
    );
    assert_eq!(
        b.send(&[0x14, 0x02, 0x06, 0x00, 0x29, 0x00, 0x05]),
        [0x14, 0x02, 0x86, 0x03]
    );
    assert_eq!(model::get(b.od(), 1, id::C1_00), 1, "unchanged");
    assert_eq!(
        b.send(&[0x15, 0x02, 0x06, 0x01, 0x10, 0x00, 0x00]),
        [0x15, 0x02, 0x86, 0x02]
    );
}

#[test]
fn channel_cmd15_answers_module_by_module_and_refuses_a_missing_module() {
    let mut b = Bench::<3>::new();
    let req = [
        0x23, 0x03, 0x0F, 0x00, 0x03, 0xE8, 0x00, 0x00, 0x00, 0x07, 0xD0, 0x00, 0x00, 0x00, 0xF4,
        0x48, 0x00, 0x00,
    ];
    let first = b.send(&req);
    assert_eq!(first[..3], [0x23, 0x01, 0x0F], "module 1 answers first");
    assert_eq!(
        model::get(b.od(), 2, id::A1_01),
        -3000,
        "module 3's set value"
    );
    let mut next = req;
    next[0] = 0x24;
    assert_eq!(b.send(&next)[..3], [0x24, 0x02, 0x0F], "then module 2");
    // Manual 5.3: module 3 is not installed and SNUM is 3.
    let mut two = Bench::<2>::new();
    assert_eq!(two.send(&req), [0x23, 0x03, 0x8F, 0x08]);
    // SNUM 0 is exception 7 (5.3), with the telegram's header.
    assert_eq!(two.send(&[0x30, 0x00, 0x0F]), [0x30, 0x00, 0x8F, 0x07]);
    // A CMD 15 shorter than SNUM says: exception 9 from the node (SADR 0).
    assert_eq!(
        two.send(&[0x31, 0x02, 0x0F, 0x00, 0x03, 0xE8, 0x00, 0x00]),
        [0x31, 0x00, 0x8F, 0x09]
    );
    // Not a telegram at all: no answer.
    assert_eq!(two.send(&[0x32]), [] as [u8; 0]);
    assert_eq!(two.send(&[0x33, 0x01, 0x42, 0x00]), [] as [u8; 0]);
}

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(2000))]

    /// Any bytes through the channel: never a panic; an answer is always a
    /// telegram the codec reads back, from a plugged module or the node.
    #[test]
    fn the_channel_answers_any_bytes_with_a_valid_telegram_or_nothing(
        telegrams in proptest::collection::vec(
            proptest::collection::vec(proptest::prelude::any::<u8>(), 0..=32),
            1..8,
        )
    ) {
        let mut b = Bench::<2>::new();
        for t in &telegrams {
            let answer = b.send(t);
            if !answer.is_empty() {
                let r = crate::telegram::ResponseRepr::parse(&answer);
                proptest::prop_assert!(r.is_ok(), "{t:02x?} -> {answer:02x?}");
                proptest::prop_assert_eq!(answer[0], t[0], "TADR echoed");
            }
        }
    }
}
