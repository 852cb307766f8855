//! What a master sees when the slave's own hardware fails or when a master
//! session ends badly: PDI failures end in the safe state with an AL error
//! code (never "all is well"), a firmware store that cannot commit is
//! reported at BOOT->INIT, and nothing queued before INIT reaches the next
//! master session.

use crate::common::{request, settle, status};
use ecat_sim::chain::{IMAGE_SLOT_CAPACITY, provision_factory};
use ecat_sim::esc::PdiFault;
use ecat_sim::image_store::VecStore;
use ecat_slave::esc::EscError;
use ecat_slave::firmware::{BootState, ImageStore, Slot, StoreError};
use ecat_slave::wire::coe::{CoeHeader, CoeService, Emergency, EmergencyRepr};
use ecat_slave::wire::mailbox::MailboxType;
use master_test::VirtualBus;
use master_test::foe::{self, enter_boot};
use master_test::link::{Chain, Clock, lock};
use master_test::mailbox::{ClientError, MailboxClient, MailboxGeometry};
use pam_199_p_etc::Pam;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

type Md = ethercrab::MainDevice<'static>;

const ERR: u16 = 0x10;

/// The next emergency in the mailbox, if one arrives within 200 ms.
async fn next_emergency(c: &mut MailboxClient<'_>) -> Option<EmergencyRepr> {
    c.timeout = Duration::from_millis(200);
    loop {
        match c.receive().await {
            Ok(m) if m.kind == MailboxType::CoE => {
                let coe = CoeHeader::new_checked(&m.payload[..]).expect("CoE header");
                if coe.service() == CoeService::Emergency {
                    let e = Emergency::new_checked(&m.payload[2..]).expect("emergency");
                    return Some(EmergencyRepr::parse(&e).expect("emergency"));
                }
            }
            Ok(_) => {}
            Err(ClientError::Timeout(_)) => return None,
            Err(e) => panic!("mailbox: {e}"),
        }
    }
}

#[test]
fn safeop_to_op_is_refused_when_the_watchdog_status_cannot_be_read() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        let group = group.into_safe_op(md).await.expect("SAFE-OP");
        group.tx_rx(md).await.expect("outputs");
        // The SM watchdog status register 0x0440 cannot be read over the PDI.
        lock(&bus.chain).slaves_mut()[0]
            .esc_mut()
            .set_pdi_fault(Some(PdiFault::reads(0x0440, 0x0442)));
        assert_eq!(
            request(md, s, 0x08).await,
            (0x04 | ERR, 0x0001),
            "refused with 0x0001, not taken as 'watchdog fine'"
        );
        assert!(lock(&bus.chain).pdi_failures() >= 1);
        let mut c = MailboxClient::new(md, s, MailboxGeometry::standard());
        let e = next_emergency(&mut c).await.expect("an emergency");
        assert_eq!(
            (e.error_code, e.data[0]),
            (0x5000, 3),
            "device hardware, interface"
        );
        // Repaired: acknowledge, then OP.
        lock(&bus.chain).slaves_mut()[0]
            .esc_mut()
            .set_pdi_fault(None);
        assert_eq!(request(md, s, 0x14).await, (0x04, 0));
        group.tx_rx(md).await.expect("outputs");
        assert_eq!(request(md, s, 0x08).await, (0x08, 0));
    });
}

#[test]
fn a_pdi_error_in_the_mailbox_check_is_a_pdi_failure_not_code_0x0016() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        assert_eq!(status(md, s).await, (0x02, 0));
        lock(&bus.chain).slaves_mut()[0]
            .esc_mut()
            .set_pdi_fault(Some(PdiFault::reads(0x0800, 0x0808)));
        settle(md).await;
        // No AL event leads to the SM registers: the firmware's full pass
        // (at most FULL_PASS_NS after the last) finds the failure.
        bus.clock
            .advance(Duration::from_nanos(ecat_slave::device::FULL_PASS_NS));
        let _ = bus.run_firmware();
        assert_eq!(
            status(md, s).await,
            (0x02 | ERR, 0x0001),
            "the mailbox is not declared misconfigured when it cannot be read"
        );
        let err = lock(&bus.chain).slaves_mut()[0].poll_with(bus.clock.now_ns(), None);
        assert_eq!(err, Err(EscError::Interface), "the caller sees the failure");
        lock(&bus.chain).slaves_mut()[0]
            .esc_mut()
            .set_pdi_fault(None);
        assert_eq!(request(md, s, 0x12).await, (0x02, 0));
    });
}

#[test]
fn a_failing_pdi_in_op_drops_to_safeop_with_outputs_and_current_off() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        let group = group.into_op(md).await.expect("OP");
        {
            let sd = group.subdevice(md, 0).expect("slave");
            let mut out = sd.outputs_raw_mut();
            out[0] = 1;
            out[1..5].copy_from_slice(&5000i32.to_le_bytes());
        }
        group.tx_rx(md).await.expect("outputs");
        for _ in 0..50 {
            bus.clock.advance(Duration::from_millis(1));
            group.tx_rx(md).await.expect("outputs");
        }
        {
            let chain = lock(&bus.chain);
            let slave = chain.slave::<Pam>(0).expect("a PAM").slave();
            assert_eq!(slave.od().get(0x7000, 1), Some(1));
            assert!(
                slave
                    .app()
                    .stage()
                    .setpoint_ma(pam_199_p_etc::board::Solenoid::A)
                    > 0
            );
        }
        // Every PDI read fails from now on (writes still reach the ESC).
        lock(&bus.chain).slaves_mut()[0]
            .esc_mut()
            .set_pdi_fault(Some(PdiFault::reads(0, u16::MAX)));
        group.tx_rx(md).await.expect("outputs");
        settle(md).await;
        assert_eq!(status(md, s).await, (0x04 | ERR, 0x0001));
        let chain = lock(&bus.chain);
        let slave = chain.slave::<Pam>(0).expect("a PAM").slave();
        assert_eq!(slave.od().get(0x7000, 1), Some(0), "ENABLE off");
        assert_eq!(slave.od().get(0x7000, 3), Some(0), "command value 0");
        for sol in [
            pam_199_p_etc::board::Solenoid::A,
            pam_199_p_etc::board::Solenoid::B,
        ] {
            assert_eq!(slave.app().stage().setpoint_ma(sol), 0, "{sol:?} off");
        }
    });
}

/// An image store that refuses every write once `fail` is set.
struct FailingStore {
    inner: VecStore,
    fail: Arc<AtomicBool>,
}

impl ImageStore for FailingStore {
    fn slot_capacity(&self) -> usize {
        self.inner.slot_capacity()
    }
    fn erase(&mut self, slot: Slot) -> Result<(), StoreError> {
        if self.fail.load(Ordering::Acquire) {
            return Err(StoreError::Io);
        }
        self.inner.erase(slot)
    }
    fn write(&mut self, slot: Slot, offset: usize, data: &[u8]) -> Result<(), StoreError> {
        if self.fail.load(Ordering::Acquire) {
            return Err(StoreError::Io);
        }
        self.inner.write(slot, offset, data)
    }
    fn read(&self, slot: Slot, offset: usize, buf: &mut [u8]) -> Result<usize, StoreError> {
        self.inner.read(slot, offset, buf)
    }
    fn read_state(&self) -> Result<BootState, StoreError> {
        self.inner.read_state()
    }
    fn write_state(&mut self, state: &BootState) -> Result<(), StoreError> {
        if self.fail.load(Ordering::Acquire) {
            return Err(StoreError::Io);
        }
        self.inner.write_state(state)
    }
}

#[test]
fn a_store_that_cannot_commit_the_image_reports_0x0007_at_boot_to_init() {
    smol::block_on(async {
        let fail = Arc::new(AtomicBool::new(false));
        let mut inner = VecStore::new(IMAGE_SLOT_CAPACITY);
        provision_factory(&mut inner).expect("factory image");
        let store = FailingStore {
            inner,
            fail: fail.clone(),
        };
        let chain = Chain::with_stores(
            vec![Box::new(ecat_sim::SoftSlave::new(
                pam_199_p_etc::Pam::default(),
            ))],
            vec![Box::new(store)],
        );
        let bus = VirtualBus::with_chain(chain, Clock::frames(), None).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        enter_boot(md, s).await.expect("BOOT");
        let mut c = MailboxClient::new(md, s, MailboxGeometry::bootstrap());
        let img = foe::pam_image("11", 3000);
        foe::write(&mut c, "pam-199-p-etc.efw", 0, &img, |_, _| {})
            .await
            .expect("download");
        // The flash dies before the bootloader hand-over is recorded.
        fail.store(true, Ordering::Release);
        let mut st = (0, 0);
        for _ in 0..50 {
            st = request(md, s, 0x01).await;
            if st.0 & 0x0F == 0x01 {
                break;
            }
        }
        assert_eq!(
            st,
            (0x01 | ERR, 0x0007),
            "INIT with 'firmware update not successful, old firmware still running'"
        );
    });
}

#[test]
fn emergencies_queued_before_init_never_reach_the_next_master_session() {
    smol::block_on(async {
        let bus = VirtualBus::with_clock(1, Clock::simulated()).expect("bus");
        let md: &Md = &bus.maindevice;
        let group = bus.init().await.expect("init");
        let s = group.subdevice(md, 0).expect("slave").configured_address();
        let group = group.into_op(md).await.expect("OP");
        group.tx_rx(md).await.expect("outputs");
        // The master stops sending outputs: SM watchdog, SAFE-OP + 0x001B,
        // emergency 0x8100 queued.
        bus.clock.advance(Duration::from_millis(101));
        settle(md).await;
        assert_eq!(status(md, s).await, (0x04 | ERR, 0x001B));
        // The master ends its session with INIT + acknowledge; clearing
        // 0x001B raises the "error reset" 0x0000 while in INIT.
        assert_eq!(request(md, s, 0x11).await, (0x01, 0));
        assert_eq!(
            lock(&bus.chain).slaves()[0].emergencies_waiting(),
            0,
            "INIT empties the emergency queue"
        );
        drop(group);

        // The next master program starts.
        let next = bus.next_session().expect("second master");
        let md2: &Md = &next.maindevice;
        let group = next.init().await.expect("the next session reaches PRE-OP");
        let s2 = group.subdevice(md2, 0).expect("slave").configured_address();
        let mut c = MailboxClient::new(md2, s2, MailboxGeometry::standard());
        assert_eq!(
            next_emergency(&mut c).await,
            None,
            "no stale emergency from the previous session"
        );
        let group = group.into_op(md2).await.expect("OP again");
        group.tx_rx(md2).await.expect("outputs");
    });
}
