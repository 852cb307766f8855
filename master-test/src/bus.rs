//! Where the tools find their slaves: the built-in virtual bus (a line of
//! software slaves in this process) or a network interface (ethercrab's
//! raw socket) with the raw-socket runner or real devices on it.

use crate::link::{Clock, lock};
use crate::{BusError, Group, MAX_FRAMES, MAX_PDU_DATA, MAX_SUBDEVICES, PDI_LEN, VirtualBus};
use ethercrab::{MainDevice, MainDeviceConfig, PduStorage, RetryBehaviour};

/// The EtherCAT segment a command talks to.
pub enum Bus {
    /// Software slaves on the virtual link.
    Virtual(VirtualBus),
    /// A network interface.
    Raw {
        /// The interface name.
        iface: String,
        /// The master on it.
        maindevice: &'static MainDevice<'static>,
        /// Real time since the bus opened.
        clock: Clock,
        /// The raw-socket link thread.
        _link: crate::link::RawLink,
    },
}

impl Bus {
    /// The virtual line `spec` (`pam`, `pam,io8,pam`, ...) with an optional
    /// capture.
    pub fn virtual_line(spec: &str, pcap: Option<&std::path::Path>) -> Result<Self, BusError> {
        Self::virtual_line_of(spec, pcap, MAX_SUBDEVICES)
    }

    /// [`Bus::virtual_line`] of at most `max` slaves (a long line for a
    /// [`crate::LongGroup`] has up to [`crate::LONG_LINE`]).
    pub fn virtual_line_of(
        spec: &str,
        pcap: Option<&std::path::Path>,
        max: usize,
    ) -> Result<Self, BusError> {
        let n = device_catalog::parse_line(spec)
            .map_err(BusError::Line)?
            .len();
        if n > max {
            return Err(BusError::LineTooLong(n, max));
        }
        Ok(Bus::Virtual(VirtualBus::line_with(
            spec,
            Clock::frames_paced(),
            pcap,
        )?))
    }

    /// The line an ENI describes on the virtual bus: each slave from the
    /// catalog or a twin from an ESI file of `esi_dir` (see
    /// `device_catalog::twins::from_eni`), inputs per `rules`.
    pub fn virtual_eni(
        eni: &std::path::Path,
        esi_dir: Option<&std::path::Path>,
        rules: &ecat_twin::InputRules,
        pcap: Option<&std::path::Path>,
    ) -> Result<Self, BusError> {
        let line = device_catalog::twins::from_eni(eni, esi_dir, rules)
            .map_err(|e| BusError::Twins(e.to_string()))?;
        if line.slaves.len() > MAX_SUBDEVICES {
            return Err(BusError::LineTooLong(line.slaves.len(), MAX_SUBDEVICES));
        }
        Ok(Bus::Virtual(VirtualBus::with_chain(
            ecat_sim::chain::Chain::with_slaves(line.slaves),
            Clock::frames_paced(),
            pcap,
        )?))
    }

    /// The segment on network interface `iface` (needs root or
    /// CAP_NET_RAW).
    pub fn raw(iface: &str) -> Result<Self, BusError> {
        // One master per process and interface: the storage lives for the
        // rest of the process.
        let storage: &'static PduStorage<MAX_FRAMES, MAX_PDU_DATA> =
            Box::leak(Box::new(PduStorage::new()));
        let (tx, rx, pdu_loop) = storage.try_split().map_err(|()| BusError::Storage)?;
        let maindevice: &'static MainDevice<'static> = Box::leak(Box::new(MainDevice::new(
            pdu_loop,
            crate::timeouts(),
            MainDeviceConfig {
                dc_static_sync_iterations: 0,
                retry_behaviour: RetryBehaviour::None,
            },
        )));
        let link = crate::link::RawLink::spawn(iface, tx, rx).map_err(|e| {
            BusError::Thread(std::io::Error::other(format!(
                "cannot open a raw socket on '{iface}': {e} (needs root or CAP_NET_RAW)"
            )))
        })?;
        Ok(Bus::Raw {
            iface: iface.to_string(),
            maindevice,
            clock: Clock::real(),
            _link: link,
        })
    }

    /// The master.
    pub fn maindevice(&self) -> &MainDevice<'static> {
        match self {
            Bus::Virtual(v) => &v.maindevice,
            Bus::Raw { maindevice, .. } => maindevice,
        }
    }

    /// The time a master on this bus waits and measures in: real time on
    /// a network interface, the slaves' (paced) frame clock on the
    /// virtual bus ([`Clock::sleep`]).
    pub fn clock(&self) -> &Clock {
        match self {
            Bus::Virtual(v) => &v.clock,
            Bus::Raw { clock, .. } => clock,
        }
    }

    /// What the bus is, for messages.
    pub fn describe(&self) -> String {
        match self {
            Bus::Virtual(_) => "the virtual bus".to_string(),
            Bus::Raw { iface, .. } => format!("interface {iface}"),
        }
    }

    /// Discovers the slaves and brings them to PRE-OP.
    pub async fn init(&self) -> Result<Group<ethercrab::subdevice_group::PreOp>, BusError> {
        self.init_group::<MAX_SUBDEVICES, PDI_LEN>().await
    }

    /// [`Bus::init`] into a group of up to `N` slaves and `P` bytes of
    /// process data (a [`crate::LongGroup`] is large: keep it off small
    /// thread stacks).
    pub async fn init_group<const N: usize, const P: usize>(
        &self,
    ) -> Result<
        ethercrab::SubDeviceGroup<N, P, ethercrab::DefaultLock, ethercrab::subdevice_group::PreOp>,
        BusError,
    > {
        Ok(self
            .maindevice()
            .init_single_group::<N, P>(ethercrab::std::ethercat_now)
            .await?)
    }

    /// How far the master has brought the slaves (virtual bus only).
    pub fn progress(&self) -> Option<crate::LineProgress> {
        match self {
            Bus::Virtual(v) => Some(crate::LineProgress::of(&lock(&v.chain))),
            Bus::Raw { .. } => None,
        }
    }

    /// The slaves of the virtual bus, shared with its link thread.
    pub fn shared_chain(&self) -> Option<crate::link::SharedChain> {
        match self {
            Bus::Virtual(v) => Some(v.chain.clone()),
            Bus::Raw { .. } => None,
        }
    }

    /// A power cycle of slave `i` (virtual bus only): the version that then
    /// runs (0x100A), `None` on a real segment.
    pub fn power_cycle(&self, i: usize) -> Option<String> {
        match self {
            Bus::Virtual(v) => lock(&v.chain).power_cycle(i),
            Bus::Raw { .. } => None,
        }
    }

    /// RUN / ERR LED patterns of the first slave (virtual bus only).
    pub fn leds(&self) -> Option<String> {
        match self {
            Bus::Virtual(v) => {
                let chain = lock(&v.chain);
                let (run, err) = chain.slaves().first()?.led_patterns();
                Some(format!("RUN {}, ERR {}", run.name(), err.name()))
            }
            Bus::Raw { .. } => None,
        }
    }
}
