//! The core crate (`slave/`, `ecat-slave`) names no device: no PAM
//! identity, name or vendor, and no object index of the device-specific
//! ranges 0x6000-0xF8FF in its code. Devices live in their own crates.

use std::path::{Path, PathBuf};

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("core source directory") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs" || x == "toml") {
            out.push(p);
        }
    }
}

fn core_files() -> Vec<PathBuf> {
    let root = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../slave"));
    let mut out = vec![root.join("Cargo.toml")];
    files(&root.join("src"), &mut out);
    assert!(out.len() > 40, "found the core's sources");
    out
}

#[test]
fn the_core_names_no_device_identity_or_name() {
    // What would betray the PAM-199-P-ETC (or its vendor) in the core,
    // tests included: names, vendor, vendor ID, product code, password.
    let forbidden = [
        "pam",
        "w.e.st",
        "0x05ae",
        "0x0000_05ae",
        "000005ae",
        "c703f3",
        "c7_03f3",
        "54534557",
    ];
    let mut hits = Vec::new();
    for f in core_files() {
        let text = std::fs::read_to_string(&f).expect("source").to_lowercase();
        for (n, line) in text.lines().enumerate() {
            for word in forbidden {
                if line.contains(word) {
                    hits.push(format!(
                        "{}:{}: {word}: {}",
                        f.display(),
                        n + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(
        hits.is_empty(),
        "device names in the core:\n{}",
        hits.join("\n")
    );
}

/// Four-digit hexadecimal literals in 0x6000..=0xF8FF that are not object
/// indices, per file (what else they are is said next to each).
const NOT_INDICES: &[(&str, &[u16])] = &[
    // ETG.2010 Table 14 PDO flag "writable".
    ("sii/mod.rs", &[0x8000]),
    // ETG.1000.6 FoE error codes 0x8000..0x8011.
    (
        "wire/foe.rs",
        &[
            0x8000, 0x8001, 0x8002, 0x8003, 0x8004, 0x8005, 0x8006, 0x8007, 0x8008, 0x8009, 0x800A,
            0x800B, 0x800C, 0x800D, 0x800F, 0x8010, 0x8011,
        ],
    ),
    // The EtherCAT EtherType.
    ("wire/ethernet.rs", &[0x88A4]),
    // Datagram header "more datagrams follow" bit.
    ("wire/ecat.rs", &[0x8000]),
    // CiA 301 emergency codes: communication (SM watchdog), refused state
    // change.
    ("coe/emergency.rs", &[0x8100, 0xA000]),
    // ETG.5001 Modular Device Profile objects, the same for every modular
    // device (like 0x1C12 for every device with PDO assignment).
    ("od/modules.rs", &[0xF000, 0xF030, 0xF050]),
    ("od/dictionary.rs", &[0xF030]),
    // ETG.1000.6 text of AL status code 0x0070, which names both lists.
    ("al.rs", &[0xF030, 0xF050]),
];

#[test]
fn the_core_code_uses_no_object_index_of_the_device_ranges() {
    let mut hits = Vec::new();
    for f in core_files() {
        let rel = f.to_string_lossy().replace('\\', "/");
        // The core's own test device is test code.
        if rel.ends_with("/testing.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("source");
        // Unit tests sit at the end of each file, after `#[cfg(test)]`.
        let code = text.split("#[cfg(test)]").next().unwrap_or("");
        let allowed: &[u16] = NOT_INDICES
            .iter()
            .find(|(file, _)| rel.ends_with(file))
            .map_or(&[], |(_, v)| v);
        for (n, line) in code.lines().enumerate() {
            let line = line.split("//").next().unwrap_or("");
            let bytes = line.as_bytes();
            let mut i = 0;
            while i + 1 < bytes.len() {
                if bytes[i] == b'0' && (bytes[i + 1] == b'x' || bytes[i + 1] == b'X') {
                    let digits: String = line[i + 2..]
                        .chars()
                        .take_while(|c| c.is_ascii_hexdigit() || *c == '_')
                        .filter(|c| *c != '_')
                        .collect();
                    if digits.len() == 4 {
                        let v = u16::from_str_radix(&digits, 16).expect("hex");
                        if (0x6000..=0xF8FF).contains(&v) && !allowed.contains(&v) {
                            hits.push(format!("{rel}:{}: {v:#06x}", n + 1));
                        }
                    }
                    i += 2 + digits.len();
                } else {
                    i += 1;
                }
            }
        }
    }
    assert!(
        hits.is_empty(),
        "device-range object indices in the core:\n{}",
        hits.join("\n")
    );
}
