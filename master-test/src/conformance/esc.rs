//! Group `esc`: ESC registers, station address and alias, DL status,
//! the EEPROM interface.

use super::*;
use crate::registers;

pub(super) async fn esc_checks(r: &mut Run<'_>) {
    let o = match r.read::<[u8; 4]>(registers::TYPE).await {
        Ok(b) => Outcome::Pass(format!(
            "type {:#04x}, revision {}, build {}",
            b[0],
            b[1],
            u16::from_le_bytes([b[2], b[3]])
        )),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.information",
        "ETG.1000.4 6.1.1",
        "ESC type, revision and build (0x0000-0x0003) readable by configured address",
        o,
    );

    let o = match r.read::<u16>(registers::STATION_ADDRESS).await {
        Ok(a) if a == r.station => Outcome::Pass(format!("{a:#06x}")),
        Ok(a) => Outcome::Fail(format!("{a:#06x}, configured {:#06x}", r.station)),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.station-address",
        "ETG.1000.4 6.2.1",
        "0x0010 holds the configured station address",
        o,
    );

    let word4 = r.sii.get(8..10).map(|b| u16::from_le_bytes([b[0], b[1]]));
    let o = match (r.read::<u16>(registers::STATION_ALIAS).await, word4) {
        (Ok(a), Some(w)) if a == w => Outcome::Pass(format!("{a:#06x} = SII word 4")),
        (Ok(a), Some(w)) => Outcome::Fail(format!("{a:#06x}, SII word 4 is {w:#06x}")),
        (Ok(_), None) => Outcome::Fail("SII unreadable".into()),
        (Err(e), _) => Outcome::Fail(e),
    };
    r.record(
        "esc.station-alias",
        "ETG.1000.4 6.2.2, ETG.2010 2.2",
        "0x0012 = configured station alias of SII word 4 (loaded at power-on)",
        o,
    );

    let o = match r.read::<u16>(registers::DL_STATUS).await {
        Ok(s) if s & 0x0010 != 0 && s & 0x0200 != 0 => {
            Outcome::Pass(format!("{s:#06x}: port 0 link and communication"))
        }
        Ok(s) => Outcome::Fail(format!(
            "{s:#06x}: port 0 physical link {} communication {}",
            s & 0x0010 != 0,
            s & 0x0200 != 0
        )),
        Err(e) => Outcome::Fail(e),
    };
    r.record(
        "esc.dl-status",
        "ETG.1000.4 6.4.3",
        "DL status 0x0110: port 0 physical link (bit 4) and communication established (bit 9)",
        o,
    );

    let a = eeprom::read(r.md, r.station, 8).await;
    let b = eeprom::read(r.md, r.station, 8).await;
    let ctl = r.read::<u16>(registers::SII_CONTROL).await;
    let o = match (a, b, ctl) {
        (Ok(a), Ok(b), Ok(c)) if a == b && c & 0x8000 == 0 && c & 0x7800 == 0 => {
            Outcome::Pass(format!(
                "words 0-7 read twice alike; {}-byte reads; status {c:#06x} not busy, no error",
                if c & 0x0040 != 0 { 8 } else { 4 }
            ))
        }
        (Ok(a), Ok(b), Ok(c)) => Outcome::Fail(format!(
            "reads {} alike; status {c:#06x}{}{}",
            if a == b { "" } else { "not" },
            if c & 0x8000 != 0 { ", busy" } else { "" },
            if c & 0x7800 != 0 {
                ", error bits set"
            } else {
                ""
            }
        )),
        (Err(e), _, _) | (_, Err(e), _) => Outcome::Fail(format!("EEPROM read: {e}")),
        (_, _, Err(e)) => Outcome::Fail(e),
    };
    r.record(
        "esc.eeprom-interface",
        "ETG.1000.4 6.4.6",
        "SII reads through 0x0500-0x050F are repeatable; afterwards not busy, no error bits",
        o,
    );
}
