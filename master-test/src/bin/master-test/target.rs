//! The segment a command talks to and the slave it selects.

use crate::failure::{Failure, input};
use master_test::bus::Bus;
use master_test::eeprom;
use master_test::mailbox::{MailboxClient, MailboxGeometry};
use master_test::{BusError, Group};

/// Where and to whom: the target of a bus command, made from the shared
/// options by [`crate::options::SharedOptions::target`] only.
#[derive(Debug, Clone, Default)]
pub struct Where {
    /// Network interface; `None`: the built-in virtual bus.
    pub iface: Option<String>,
    /// The virtual line (`pam`, `pam,io8`, `io8*3`).
    pub line: String,
    /// Selected slave by position (0 = first after the master).
    pub slave: Option<usize>,
    /// Selected slave by configured station address.
    pub station: Option<u16>,
    /// Capture of the virtual link.
    pub pcap: Option<std::path::PathBuf>,
    /// The virtual bus as the line of an ENI file: (ENI, ESI directory).
    pub eni: Option<(std::path::PathBuf, Option<std::path::PathBuf>)>,
}

/// The bus `w` names, not yet initialised; a virtual line of more than
/// `max` slaves is refused.
pub fn connect(w: &Where, max: usize) -> Result<Bus, Failure> {
    Ok(match &w.iface {
        Some(iface) => Bus::raw(iface).map_err(|e| Failure::Comm(e.to_string()))?,
        None if w.eni.is_some() => {
            let (eni, dir) = w.eni.as_ref().map(|(e, d)| (e, d.as_deref())).unzip();
            let eni = eni.ok_or_else(|| input("no ENI"))?;
            Bus::virtual_eni(
                eni,
                dir.flatten(),
                &ecat_twin::InputRules::default(),
                w.pcap.as_deref(),
            )?
        }
        None => Bus::virtual_line_of(&w.line, w.pcap.as_deref(), max).map_err(|e| {
            match (&w.pcap, e) {
                (Some(p), BusError::Thread(e)) => {
                    input(format!("cannot write the capture {}: {e}", p.display()))
                }
                (_, e) => e.into(),
            }
        })?,
    })
}

/// The group `init` gave on `bus`, or the failure naming the bus (no
/// slave at all is a failure too).
pub fn initialised<const N: usize, const P: usize>(
    bus: &Bus,
    group: Result<
        ethercrab::SubDeviceGroup<N, P, ethercrab::DefaultLock, ethercrab::subdevice_group::PreOp>,
        BusError,
    >,
) -> Result<
    ethercrab::SubDeviceGroup<N, P, ethercrab::DefaultLock, ethercrab::subdevice_group::PreOp>,
    Failure,
> {
    let group =
        group.map_err(|e| Failure::from(e).context(format!("no slaves on {}", bus.describe())))?;
    if group.is_empty() {
        return Err(Failure::Comm(format!(
            "no slave answered on {}",
            bus.describe()
        )));
    }
    Ok(group)
}

/// An open segment with every slave in PRE-OP (ethercrab's
/// `init_single_group`: addresses, SII, mailboxes, process data image).
pub struct Session {
    /// The bus.
    pub bus: Bus,
    /// All slaves.
    pub group: Group<ethercrab::subdevice_group::PreOp>,
}

/// The slave a command talks to.
pub struct Selected {
    /// Position on the segment.
    pub position: usize,
    /// Configured station address.
    pub station: u16,
    /// Name (SII).
    pub name: String,
    /// Identity (SII).
    pub identity: ethercrab::SubDeviceIdentity,
    /// SII header words 0x00-0x3F.
    pub header: Vec<u8>,
    /// The catalog device with this identity, if it is one of ours.
    pub device: Option<&'static device_catalog::DeviceEntry>,
}

impl Selected {
    /// `slave 0 (0x1000 PAM-199-P-ETC)`.
    pub fn label(&self) -> String {
        format!(
            "slave {} ({:#06x} {})",
            self.position, self.station, self.name
        )
    }

    /// The standard mailbox from the SII, or why there is none.
    pub fn mailbox(&self) -> Result<MailboxGeometry, Failure> {
        eeprom::mailboxes(&self.header).0.ok_or_else(|| {
            input(format!(
                "{} has no mailbox (SII words 0x18-0x1B are 0): no SDO or FoE",
                self.label()
            ))
        })
    }

    /// The bootstrap mailbox from the SII, or why there is none.
    pub fn bootstrap(&self) -> Result<MailboxGeometry, Failure> {
        eeprom::mailboxes(&self.header).1.ok_or_else(|| {
            input(format!(
                "{} has no bootstrap mailbox (SII words 0x14-0x17 are 0): no BOOT, \
                 no firmware update",
                self.label()
            ))
        })
    }
}

/// The catalog device with `vendor`/`product`.
pub fn device_by_identity(
    vendor: u32,
    product: u32,
) -> Option<&'static device_catalog::DeviceEntry> {
    device_catalog::DEVICES.iter().find(|d| {
        d.description.identity.vendor_id == vendor && d.description.identity.product_code == product
    })
}

impl Session {
    /// Opens the bus of `w` and brings every slave to PRE-OP.
    pub async fn open(w: &Where) -> Result<Self, Failure> {
        let bus = connect(w, master_test::MAX_SUBDEVICES)?;
        let group = bus.init().await;
        let group = initialised(&bus, group)?;
        Ok(Session { bus, group })
    }

    /// The master.
    pub fn md(&self) -> &ethercrab::MainDevice<'static> {
        self.bus.maindevice()
    }

    /// The slave `w` selects: `--slave N`, `--station ADDR`, or the only
    /// one.
    pub async fn select(&self, w: &Where) -> Result<Selected, Failure> {
        let md = self.md();
        let n = self.group.len();
        let position = match (w.slave, w.station) {
            (Some(p), _) if p >= n => {
                return Err(input(format!(
                    "--slave {p}: {} has {n} slave(s), positions 0..={}",
                    self.bus.describe(),
                    n - 1
                )));
            }
            (Some(p), _) => p,
            (None, Some(station)) => self
                .group
                .iter(md)
                .position(|sd| sd.configured_address() == station)
                .ok_or_else(|| {
                    let list: Vec<String> = self
                        .group
                        .iter(md)
                        .map(|sd| format!("{:#06x}", sd.configured_address()))
                        .collect();
                    input(format!(
                        "--station {station:#06x}: no such slave (stations: {})",
                        list.join(", ")
                    ))
                })?,
            (None, None) if n == 1 => 0,
            (None, None) => {
                return Err(input(format!(
                    "{} has {n} slaves: choose one with --slave 0..={} or --station ADDR \
                     (see `master-test scan`)",
                    self.bus.describe(),
                    n - 1
                )));
            }
        };
        let sd = self.group.subdevice(md, position)?;
        let station = sd.configured_address();
        let identity = sd.identity();
        let header = eeprom::read_header(md, station).await?;
        Ok(Selected {
            position,
            station,
            name: sd.name().to_string(),
            identity,
            header,
            device: device_by_identity(identity.vendor_id, identity.product_id),
        })
    }

    /// A mailbox client for `s` (standard mailbox), naming enumeration
    /// values with `s`'s device dictionary where it is one of ours.
    pub fn client(&self, s: &Selected) -> Result<MailboxClient<'_>, Failure> {
        let geometry = s.mailbox()?;
        master_test::cli::use_enums(
            s.device
                .map_or(&[][..], |d| d.description.dictionary.enums()),
        );
        Ok(MailboxClient::new(self.md(), s.station, geometry))
    }
}
