//! Reading an EtherCAT Network Information file (ENI, ETG.2100) for a
//! line of twins.
//!
//! What a line of twins needs from `EtherCATConfig/Config/Slave`, in file
//! order: `Info` (name, physical and auto-increment address, vendor,
//! product code, revision, serial; the station alias from
//! `Info/Identification` when it identifies by register 0x0012),
//! `ProcessData` (`Send`/`Recv` bit lengths: the process image the
//! configurator laid out) and the number of init commands (register
//! `InitCmds` and CoE `Mailbox/CoE/InitCmds`). The init commands
//! themselves are for the master; the twins answer them as the real
//! devices would.

use crate::esi::At;
use crate::xml::{self, Element};

/// One CoE init command of an ENI slave (`Mailbox/CoE/InitCmds/InitCmd`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CoeInitCmd {
    /// Transitions it runs in (`IP`, `PS`, ...).
    pub transitions: Vec<String>,
    /// Object index.
    pub index: u16,
    /// Subindex.
    pub sub: u8,
    /// Data downloaded (little-endian).
    pub data: Vec<u8>,
    /// Complete access.
    pub complete_access: bool,
}

/// One slave of an ENI.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct EniSlave {
    /// `Info/Name`.
    pub name: String,
    /// `Info/PhysAddr`: the station address the master assigns.
    pub phys_addr: u16,
    /// `Info/AutoIncAddr` (0, 0xFFFF, 0xFFFE, ...).
    pub auto_inc_addr: u16,
    /// Vendor ID.
    pub vendor_id: u32,
    /// Product code.
    pub product_code: u32,
    /// Revision number.
    pub revision: u32,
    /// Serial number.
    pub serial: u32,
    /// Station alias the slave must hold in its SII (word 4), if the ENI
    /// identifies it by alias.
    pub alias: Option<u16>,
    /// Output bits the process image gives it (`ProcessData/Send`).
    pub output_bits: u32,
    /// Input bits (`ProcessData/Recv`).
    pub input_bits: u32,
    /// Register init commands (`InitCmds/InitCmd`).
    pub init_cmds: usize,
    /// CoE init commands (`Mailbox/CoE/InitCmds/InitCmd`).
    pub coe_init_cmds: usize,
    /// Those of them that download data, in order.
    pub coe_init: Vec<CoeInitCmd>,
    /// Where it is in the file.
    pub at: At,
}

/// Why an ENI cannot describe a line.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum EniError {
    /// Not well-formed XML.
    #[error("not well-formed XML: {0}")]
    Xml(#[from] xml::XmlError),
    /// The root is not `EtherCATConfig`.
    #[error("root element is <{0}>, not <EtherCATConfig>")]
    NotEni(String),
    /// A required element is missing.
    #[error("{at}: missing {what}")]
    Missing {
        /// The element lacking it.
        at: At,
        /// What.
        what: &'static str,
    },
    /// A value cannot be read.
    #[error("{at}: bad {what} '{value}'")]
    BadValue {
        /// The element.
        at: At,
        /// What it is.
        what: &'static str,
        /// Its text.
        value: String,
    },
    /// The ENI has no slave.
    #[error("the ENI describes no <Slave>")]
    NoSlaves,
}

pub use crate::xml::number;

fn value<T: TryFrom<i64>>(e: &Element, what: &'static str) -> Result<T, EniError> {
    number(&e.text)
        .and_then(|v| T::try_from(v).ok())
        .ok_or_else(|| EniError::BadValue {
            at: At::of(e),
            what,
            value: e.text.clone(),
        })
}

fn req<'a>(e: &'a Element, name: &'static str) -> Result<&'a Element, EniError> {
    e.child(name).ok_or_else(|| EniError::Missing {
        at: At::of(e),
        what: name,
    })
}

fn opt<T: TryFrom<i64>>(e: &Element, name: &'static str) -> Result<Option<T>, EniError> {
    e.child(name).map(|c| value(c, name)).transpose()
}

fn bits(pd: Option<&Element>, dir: &str) -> Result<u32, EniError> {
    let Some(pd) = pd else { return Ok(0) };
    let mut total = 0u32;
    for d in pd.children_named(dir) {
        total = total.saturating_add(opt::<u32>(d, "BitLength")?.unwrap_or(0));
    }
    Ok(total)
}

fn parse_slave(s: &Element) -> Result<EniSlave, EniError> {
    let info = req(s, "Info")?;
    let alias = match info.child("Identification") {
        Some(id) => {
            let ado: Option<u16> = opt(id, "Ado")?;
            match ado {
                None | Some(0x0012) => opt(id, "Value")?,
                Some(_) => None,
            }
        }
        None => None,
    };
    let pd = s.child("ProcessData");
    let coe_init_cmds = s
        .path("Mailbox/CoE/InitCmds")
        .map_or(0, |i| i.children_named("InitCmd").count());
    let mut coe_init = Vec::new();
    if let Some(cmds) = s.path("Mailbox/CoE/InitCmds") {
        for c in cmds.children_named("InitCmd") {
            let Some(data) = c.child("Data") else {
                continue;
            };
            coe_init.push(CoeInitCmd {
                transitions: c
                    .children_named("Transition")
                    .map(|t| t.text.trim().to_string())
                    .collect(),
                index: value(req(c, "Index")?, "Index")?,
                sub: opt(c, "SubIndex")?.unwrap_or(0),
                data: crate::xml::hex_binary(&data.text).ok_or_else(|| EniError::BadValue {
                    at: At::of(data),
                    what: "Data",
                    value: data.text.clone(),
                })?,
                complete_access: matches!(c.attr("CompleteAccess"), Some("1" | "true")),
            });
        }
    }
    Ok(EniSlave {
        name: info.text_at("Name").unwrap_or("").to_string(),
        phys_addr: opt(info, "PhysAddr")?.unwrap_or(0),
        auto_inc_addr: opt(info, "AutoIncAddr")?.unwrap_or(0),
        vendor_id: value(req(info, "VendorId")?, "VendorId")?,
        product_code: value(req(info, "ProductCode")?, "ProductCode")?,
        revision: opt(info, "RevisionNo")?.unwrap_or(0),
        serial: opt(info, "SerialNo")?.unwrap_or(0),
        alias: alias.filter(|a| *a != 0),
        output_bits: bits(pd, "Send")?,
        input_bits: bits(pd, "Recv")?,
        init_cmds: s
            .child("InitCmds")
            .map_or(0, |i| i.children_named("InitCmd").count()),
        coe_init_cmds,
        coe_init,
        at: At::of(s),
    })
}

/// The slaves of an ENI document, in line order.
pub fn parse(text: &str) -> Result<Vec<EniSlave>, EniError> {
    let root = xml::parse(text)?;
    if root.name != "EtherCATConfig" {
        return Err(EniError::NotEni(root.name.clone()));
    }
    let config = req(&root, "Config")?;
    let slaves = config
        .children_named("Slave")
        .map(parse_slave)
        .collect::<Result<Vec<_>, _>>()?;
    if slaves.is_empty() {
        return Err(EniError::NoSlaves);
    }
    Ok(slaves)
}

#[cfg(test)]
mod tests {
    use super::*;

    const ENI: &str = r#"<?xml version="1.0"?>
<EtherCATConfig Version="1.3">
  <Config>
    <Master><Info><Name>M</Name></Info></Master>
    <Slave>
      <Info>
        <Name>Term 1 (EK1100)</Name>
        <PhysAddr>1001</PhysAddr>
        <AutoIncAddr>0</AutoIncAddr>
        <VendorId>2</VendorId>
        <ProductCode>#x044c2c52</ProductCode>
        <RevisionNo>0x00120000</RevisionNo>
        <SerialNo>0</SerialNo>
      </Info>
      <InitCmds><InitCmd/><InitCmd/></InitCmds>
    </Slave>
    <Slave>
      <Info>
        <Name>Term 2 (EL2004)</Name>
        <PhysAddr>1002</PhysAddr>
        <AutoIncAddr>65535</AutoIncAddr>
        <Identification><Ado>#x0012</Ado><Value>7</Value></Identification>
        <VendorId>2</VendorId>
        <ProductCode>131346514</ProductCode>
        <RevisionNo>1048576</RevisionNo>
      </Info>
      <ProcessData><Send><BitStart>0</BitStart><BitLength>4</BitLength></Send></ProcessData>
    </Slave>
  </Config>
</EtherCATConfig>"#;

    #[test]
    fn eni_slaves_are_read_in_order_with_addresses_identity_and_sizes() {
        let s = parse(ENI).unwrap();
        assert_eq!(s.len(), 2);
        assert_eq!(s[0].phys_addr, 1001);
        assert_eq!(s[0].product_code, 0x044c_2c52);
        assert_eq!(s[0].revision, 0x0012_0000);
        assert_eq!(s[0].init_cmds, 2);
        assert_eq!(s[0].alias, None);
        assert_eq!(s[1].auto_inc_addr, 0xFFFF);
        assert_eq!(s[1].product_code, 0x07d4_3052);
        assert_eq!(s[1].alias, Some(7));
        assert_eq!(s[1].output_bits, 4);
        assert_eq!(s[1].at.line, 17);
    }

    #[test]
    fn coe_init_commands_are_read_with_their_data() {
        let eni = ENI.replace(
            "</Info>\n      <InitCmds>",
            "</Info>\n      <Mailbox><CoE><InitCmds><InitCmd CompleteAccess=\"1\"><Transition>PS</Transition><Transition>SO</Transition><Index>#xf030</Index><SubIndex>1</SubIndex><Data>01002200</Data></InitCmd></InitCmds></CoE></Mailbox>\n      <InitCmds>",
        );
        let s = parse(&eni).unwrap();
        let c = &s[0].coe_init[0];
        assert_eq!((c.index, c.sub, c.complete_access), (0xF030, 1, true));
        assert_eq!(c.data, [1, 0, 0x22, 0]);
        assert_eq!(c.transitions, ["PS", "SO"]);
        let bad = eni.replace("<Data>01002200</Data>", "<Data>0100220</Data>");
        assert!(
            parse(&bad)
                .unwrap_err()
                .to_string()
                .contains("bad Data '0100220'")
        );
    }

    #[test]
    fn eni_errors_name_the_element_and_line() {
        let bad = ENI.replace(
            "<VendorId>2</VendorId>\n        <ProductCode>131346514",
            "<VendorId>x2</VendorId>\n        <ProductCode>131346514",
        );
        let e = parse(&bad).unwrap_err();
        assert_eq!(e.to_string(), "<VendorId> at line 23: bad VendorId 'x2'");
        let e = parse("<EtherCATConfig><Config/></EtherCATConfig>").unwrap_err();
        assert_eq!(e, EniError::NoSlaves);
        let e = parse("<EtherCATInfo/>").unwrap_err();
        assert!(e.to_string().contains("not <EtherCATConfig>"), "{e}");
        let e = parse("<EtherCATConfig><Config><Slave><Info><Name>x</Name></Info></Slave></Config></EtherCATConfig>").unwrap_err();
        assert!(e.to_string().contains("missing VendorId"), "{e}");
    }
}
