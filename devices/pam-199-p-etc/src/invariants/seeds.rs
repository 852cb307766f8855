//! Master sessions that reach every corner the invariants talk about:
//! the fuzz target's committed seeds (`fuzz/examples/seed.rs` writes them
//! with [`super::encode`]) and a test that runs each through the harness.

use std::vec;
use std::vec::Vec;

use super::action::{
    Action, Coil, Image, Outputs, PdiRegion, Request, SmSetting, StageEvent, Target, Value,
};

fn download(index: u16, sub: u8, value: Value) -> Action {
    Action::Download {
        index,
        sub,
        value,
        complete: None,
    }
}

fn cycles(count: u8, enable: u8, command: i32) -> Action {
    Action::Cycles {
        count,
        outputs: Outputs::Values { enable, command },
    }
}

fn request(state: Request) -> Action {
    Action::Request { state, ack: true }
}

const fn foe(image: Image, cut_after: Option<u16>) -> Action {
    Action::Foe {
        image,
        password: true,
        stop_after: None,
        cut_after,
    }
}

const OP: Action = Action::BringUp { target: Target::Op };
const PRE_OP: Action = Action::BringUp {
    target: Target::PreOp,
};
const BOOT: Action = Action::BringUp {
    target: Target::Boot,
};

/// Named sessions (name, actions).
pub fn seeds() -> Vec<(&'static str, Vec<Action>)> {
    vec![
        (
            "op-frames-stop-and-resume",
            vec![
                OP,
                cycles(100, 1, 5000),
                Action::Silence { ms: 150 },
                cycles(10, 1, 5000),
                request(Request::Op),
                cycles(50, 1, -5000),
                Action::TimeJump { ms: 600_000 },
                cycles(5, 1, 0),
            ],
        ),
        (
            "independent-mode",
            vec![
                PRE_OP,
                download(0xF800, 2, Value::Two),
                OP,
                cycles(100, 0x07, 8000),
                download(0x7010, 1, Value::Zero),
                request(Request::PreOp),
                download(0xF801, 3, Value::One),
                OP,
            ],
        ),
        (
            "firmware-update",
            vec![
                BOOT,
                foe(Image::Good, None),
                request(Request::Init),
                Action::PowerCycle { confirm: true },
                OP,
                cycles(20, 1, 3000),
            ],
        ),
        (
            "firmware-update-cut-and-rolled-back",
            vec![
                BOOT,
                foe(Image::Good, Some(100)),
                BOOT,
                foe(Image::Corrupt { at: 77 }, None),
                foe(Image::Good, None),
                request(Request::Init),
                Action::PowerCycle { confirm: false },
                Action::PowerCycle { confirm: false },
                Action::PowerCycle { confirm: false },
                Action::PowerCycle { confirm: false },
                PRE_OP,
            ],
        ),
        (
            "firmware-decayed-after-download",
            vec![
                BOOT,
                foe(Image::Good, None),
                request(Request::Init),
                Action::CorruptSlot { at: 40, mask: 0 },
                Action::PowerCycle { confirm: true },
                BOOT,
                foe(Image::Old, None),
                foe(Image::OtherProduct, None),
            ],
        ),
        (
            "vendor-password",
            vec![
                PRE_OP,
                download(0xF801, 1, Value::Password),
                download(0xF80F, 1, Value::Raw(1234)),
                download(0xF801, 2, Value::One),
                download(0xF80F, 1, Value::Raw(4321)),
                download(0xF801, 1, Value::Zero),
                Action::TimeJump { ms: 1_200 },
                download(0xF801, 3, Value::One),
                download(0xF801, 4, Value::One),
                download(0xF801, 1, Value::Password),
                request(Request::Init),
                PRE_OP,
                download(0xF80F, 1, Value::Raw(7)),
                Action::PowerCycle { confirm: true },
            ],
        ),
        (
            "save-cut-in-the-middle",
            vec![
                PRE_OP,
                download(0xF800, 2, Value::Two),
                Action::CutSave { after: 300 },
                PRE_OP,
                download(0xF800, 2, Value::Two),
                download(0xF801, 2, Value::One),
                download(0xF801, 2, Value::One),
                Action::CorruptNv { at: 20, xor: 0x10 },
                Action::PowerCycle { confirm: true },
                OP,
                cycles(50, 0x07, 5000),
            ],
        ),
        (
            "pdi-faults-in-op",
            vec![
                OP,
                Action::PdiFault {
                    region: PdiRegion::All,
                    reads: true,
                    writes: true,
                    ms: 5,
                },
                cycles(10, 1, 5000),
                request(Request::Op),
                Action::PdiFault {
                    region: PdiRegion::ProcessData,
                    reads: true,
                    writes: false,
                    ms: 20,
                },
                OP,
                Action::PdiFault {
                    region: PdiRegion::Watchdog,
                    reads: true,
                    writes: false,
                    ms: 200,
                },
                Action::Stall { ms: 300 },
                cycles(20, 1, 5000),
            ],
        ),
        (
            "sm-watchdog-disabled-and-state-requests",
            vec![
                OP,
                Action::Watchdog { time: 0 },
                cycles(150, 1, 5000),
                Action::Watchdog { time: 1000 },
                Action::Silence { ms: 200 },
                Action::ProcessData {
                    sm2: SmSetting::Off,
                    sm3: SmSetting::Image,
                },
                Action::Request {
                    state: Request::SafeOp,
                    ack: false,
                },
                Action::Request {
                    state: Request::Raw(6),
                    ack: true,
                },
                Action::ProcessData {
                    sm2: SmSetting::Len(0),
                    sm3: SmSetting::Default,
                },
                request(Request::SafeOp),
            ],
        ),
        (
            "assignment-by-complete-access",
            vec![
                PRE_OP,
                Action::Download {
                    index: 0x1C12,
                    sub: 0,
                    value: Value::Pdo(1),
                    complete: Some(2),
                },
                Action::ProcessData {
                    sm2: SmSetting::Image,
                    sm3: SmSetting::Image,
                },
                request(Request::SafeOp),
                Action::Upload {
                    index: 0x1C13,
                    sub: 0,
                    complete: true,
                },
                download(0x1C12, 0, Value::Zero),
                Action::Download {
                    index: 0xF800,
                    sub: 0,
                    value: Value::Two,
                    complete: Some(3),
                },
            ],
        ),
        (
            "stage-faults-and-sens",
            vec![
                OP,
                cycles(50, 1, 5000),
                Action::Stage(StageEvent::OpenWire(Coil::A)),
                cycles(20, 1, 5000),
                Action::Stage(StageEvent::Clear),
                download(0xF800, 3, Value::Raw(3)),
                Action::Stage(StageEvent::Supply(10)),
                cycles(50, 1, 5000),
                Action::Stage(StageEvent::Clear),
                cycles(255, 1, 5000),
            ],
        ),
        (
            "boot-records-unreadable",
            vec![
                Action::BootRecords { readable: false },
                Action::PowerCycle { confirm: true },
                PRE_OP,
                BOOT,
                foe(Image::Good, None),
                Action::BootRecords { readable: true },
                BOOT,
                foe(Image::Good, None),
                request(Request::Init),
                Action::PowerCycle { confirm: true },
                OP,
            ],
        ),
        (
            "sdo-written-enable-in-op",
            vec![
                OP,
                cycles(10, 0, 6000),
                download(0x7000, 1, Value::One),
                Action::Silence { ms: 20 },
            ],
        ),
    ]
}
