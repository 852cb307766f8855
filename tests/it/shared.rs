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

/// The vendors' ESI files of the corpus (`ESI_CORPUS_DIR`, which
/// `scripts/shared-checks.sh` points at `../shared/esi-corpus`).
fn corpus() -> PathBuf {
    let dir = std::env::var_os("ESI_CORPUS_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| panic!("ESI_CORPUS_DIR is not set (scripts/shared-checks.sh)"));
    assert!(dir.is_dir(), "{}: not a folder", dir.display());
    dir
}

/// Issue 28's acceptance through SOEM: twins of five real devices from
/// their vendors' own ESI files (a coupler, digital input and output
/// terminals, an analog input terminal with CoE and a CiA 402 servo drive
/// whose ESI has REAL objects and writable PDO mappings) on `pam-slave
/// --eni --esi-dir` over veth. SOEM finds them with the identities and
/// names the ESIs give, writes a mapping of its own into the drive in its
/// configuration hook, configures DC, brings the line to OP and enables
/// the drive in CSP; the position follows a ramp (the script's `corpus`
/// phase; its log is target/interop-logs/soem-corpus.log).
#[test]
#[ignore = "needs the ESI corpus in ESI_CORPUS_DIR (scripts/shared-checks.sh)"]
fn soem_runs_twins_of_five_real_devices_from_their_esi_files_and_enables_a_drive_in_csp() {
    let src = corpus();
    // (file, device type): the highest revision of each.
    let line = [
        ("beckhoff__Beckhoff EK11xx.xml", "EK1100"),
        ("beckhoff__Beckhoff EL1xxx.xml", "EL1008"),
        ("beckhoff__Beckhoff EL2xxx.xml", "EL2008"),
        ("beckhoff__Beckhoff EL3xxx.xml", "EL3602"),
        ("ingenia__evs-xcr-e_esi.xml", "EVS-XCR-E"),
    ];
    let dir = std::env::temp_dir().join(format!("pam-soem-corpus-{}", std::process::id()));
    let esi_dir = dir.join("esi");
    std::fs::create_dir_all(&esi_dir).expect("dir");
    let mut slaves = String::new();
    let mut spec = Vec::new();
    for (k, (file, ty)) in line.iter().enumerate() {
        let path = src.join(file);
        let bytes = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        std::fs::write(esi_dir.join(file), &bytes).expect("copy");
        let esi = ecat_twin::EsiFile::parse_bytes(&bytes).expect("the ESI loads");
        let dev = esi
            .devices
            .iter()
            .filter(|d| d.type_name == *ty)
            .max_by_key(|d| d.revision)
            .unwrap_or_else(|| panic!("{file}: no device {ty}"));
        if *ty == "EVS-XCR-E" {
            let (desc, _) = ecat_twin::coe_twin::describe(dev).expect("the drive's twin");
            let dict = desc.dictionary;
            assert!(ecat_cia402::Cia402Axis::is_cia402(dict), "a CiA 402 drive");
            let real = dict.objects().iter().any(|o| {
                o.entries
                    .iter()
                    .any(|e| e.data_type == ecat_slave::od::DataType::Real32)
            });
            assert!(real, "the drive's ESI has REAL objects");
            assert_eq!(
                ecat_slave::pdo::sii_flags(dict, 0x1600),
                0,
                "0x1600 is not fixed"
            );
        }
        slaves += &format!(
            "<Slave><Info><Name>Term {n} ({ty})</Name><PhysAddr>{addr}</PhysAddr><AutoIncAddr>{auto}</AutoIncAddr>\
             <VendorId>{v}</VendorId><ProductCode>{p}</ProductCode><RevisionNo>{r}</RevisionNo></Info></Slave>\n",
            n = k + 1,
            addr = 1001 + k,
            auto = (0u16).wrapping_sub(k as u16),
            v = dev.vendor_id,
            p = dev.product_code,
            r = dev.revision,
        );
        spec.push(format!(
            "{ty}|{:#x}|{:#x}|{:#x}",
            dev.vendor_id, dev.product_code, dev.revision
        ));
    }
    let eni = format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<EtherCATConfig Version=\"1.3\"><Config>\
         <Master><Info><Name>Corpus line</Name></Info></Master>\n{slaves}</Config></EtherCATConfig>\n"
    );
    let eni_path = dir.join("corpus.xml");
    std::fs::write(&eni_path, eni).expect("ENI");
    let eni_arg = eni_path.to_str().expect("utf-8 path").to_string();
    let spec = spec.join(";");
    crate::soem::soem_phase(
        "c",
        "corpus",
        "",
        &[
            "--eni",
            &eni_arg,
            "--esi-dir",
            esi_dir.to_str().expect("utf-8 path"),
        ],
        &["corpus", &spec, "5"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}
