//! Checks on data that may not be committed with the repository: the
//! ETG.2000 schema (`EtherCATInfo.xsd`, distributed by the EtherCAT
//! Technology Group; its redistribution terms are not known to us).
//!
//! These tests are `#[ignore]`d, so the README's test command never needs
//! anything beside the clone. `scripts/shared-checks.sh` runs them with the
//! folder given by `ESI_SCHEMA_DIR` (`.ci/run` points it at
//! `../shared/esi-schema`); outside CI, without the folder, the script says
//! SKIPPED.

use std::path::{Path, PathBuf};
use std::process::Command;

/// Why these tests are ignored by default.
const NEEDS: &str = "needs the ETG.2000 schema in ESI_SCHEMA_DIR (scripts/shared-checks.sh)";

/// `EtherCATInfo.xsd` from `ESI_SCHEMA_DIR`; a clear failure without it
/// (these tests only run when asked for).
fn schema() -> PathBuf {
    let dir = std::env::var_os("ESI_SCHEMA_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| panic!("ESI_SCHEMA_DIR is not set: {NEEDS}"));
    let xsd = dir.join("EtherCATInfo.xsd");
    assert!(xsd.is_file(), "{}: not found", xsd.display());
    xsd
}

/// Validates `xml` (named `name` in messages) with xmllint against the
/// ETG.2000 schema.
fn validate(name: &str, xml: &[u8]) {
    let file = std::env::temp_dir().join(format!(
        "ecat-schema-{}-{}.xml",
        std::process::id(),
        name.replace(['/', ' '], "_")
    ));
    std::fs::write(&file, xml).expect("temporary file");
    let out = Command::new("xmllint")
        .arg("--noout")
        .arg("--schema")
        .arg(schema())
        .arg(&file)
        .output();
    let _ = std::fs::remove_file(&file);
    let out = out.unwrap_or_else(|e| panic!("xmllint: {e} (install libxml2-utils)"));
    assert!(
        out.status.success(),
        "{name}: xmllint: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
#[ignore = "needs the ETG.2000 schema in ESI_SCHEMA_DIR (scripts/shared-checks.sh)"]
fn every_catalog_devices_generated_esi_validates_against_the_etg_schema() {
    for d in device_catalog::DEVICES {
        let xml = ecat_esi::generate(d.description).expect("ESI");
        validate(d.key, &xml);
    }
    assert!(device_catalog::DEVICES.len() >= 6, "servo402 among them");
}

#[test]
#[ignore = "needs the ETG.2000 schema in ESI_SCHEMA_DIR (scripts/shared-checks.sh)"]
fn the_twin_test_esi_files_validate_against_the_etg_schema() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/testdata/esi");
    let mut n = 0;
    for f in std::fs::read_dir(&dir).expect("twin/testdata/esi") {
        let p = f.expect("entry").path();
        if p.extension().is_some_and(|x| x == "xml") {
            validate(&p.display().to_string(), &std::fs::read(&p).expect("read"));
            n += 1;
        }
    }
    assert!(n >= 3, "{n} files");
}
