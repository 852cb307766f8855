use super::*;
use ecat_slave::sii::pdo_flags;

const ONE: &str = r##"<?xml version="1.0"?>
<EtherCATInfo>
  <Vendor><Id>#x00000002</Id><Name>V</Name></Vendor>
  <Descriptions>
    <Groups><Group><Type>DigOut</Type><Name>Outputs</Name></Group></Groups>
    <Devices>
      <Device Physics="KK">
        <Type ProductCode="#x07d43052" RevisionNo="#x00100000">EL2004</Type>
        <Name LcId="1031">Deutsch</Name>
        <Name LcId="1033">English</Name>
        <GroupType>DigOut</GroupType>
        <Fmmu>Outputs</Fmmu>
        <Sm StartAddress="#x0f00" ControlByte="#x44" Enable="1" OpOnly="1">Outputs</Sm>
        <RxPdo Fixed="1" Mandatory="1" Sm="0">
          <Index>#x1600</Index><Name>Channel 1</Name>
          <Exclude>#x1601</Exclude>
          <Entry><Index>#x7000</Index><SubIndex>1</SubIndex><BitLen>1</BitLen><Name>Output</Name><DataType>BOOL</DataType></Entry>
          <Entry><Index>#x0</Index><BitLen>3</BitLen></Entry>
        </RxPdo>
        <Eeprom><ByteSize>2048</ByteSize><ConfigData>0401000000000F00</ConfigData></Eeprom>
      </Device>
    </Devices>
  </Descriptions>
</EtherCATInfo>"##;

#[test]
fn a_device_is_read_with_identity_names_sms_pdos_and_eeprom() {
    let f = EsiFile::parse(ONE).unwrap();
    let d = f.device(None, None).unwrap();
    assert_eq!(
        (d.vendor_id, d.product_code, d.revision),
        (2, 0x07d4_3052, 0x0010_0000)
    );
    assert_eq!(d.name, "English", "LcId 1033 preferred");
    assert_eq!(d.group_name, "Outputs");
    assert_eq!(d.sms[0].enable, 0x09, "enable + OpOnly");
    assert_eq!(d.sms[0].kind, SmType::ProcessOut);
    let p = &d.rx_pdos[0];
    assert_eq!(p.flags, pdo_flags::MANDATORY | pdo_flags::FIXED_CONTENT);
    assert_eq!(p.excludes, [0x1601]);
    assert_eq!(p.entries[1].data_type, 0, "padding");
    assert_eq!(p.bits(), 4);
    assert_eq!(d.output_bytes(), 1);
    assert_eq!(d.config_data, [4, 1, 0, 0, 0, 0, 0x0F, 0]);
    assert!(!d.has_mailbox());
}

#[test]
fn device_choice_by_type_and_revision_and_its_errors() {
    let two = ONE.replace(
        "</Device>\n    </Devices>",
        "</Device>\n<Device><Type ProductCode=\"#x1\" RevisionNo=\"#x2\">EL9999</Type><Name>x</Name></Device>\n    </Devices>",
    );
    let f = EsiFile::parse(&two).unwrap();
    assert!(matches!(
        f.device(None, None),
        Err(EsiError::Ambiguous { count: 2, .. })
    ));
    assert_eq!(f.device(Some("el9999"), None).unwrap().revision, 2);
    let e = f.device(Some("EL2004"), Some(5)).unwrap_err();
    assert!(
        e.to_string().contains("no device EL2004 rev 0x00000005"),
        "{e}"
    );
    assert!(f.find_identity(2, 0x07d4_3052, None).is_some());
    assert!(f.find_identity(2, 0x07d4_3052, Some(1)).is_none());
}

/// Why the file's (first) device does not load, or the file's error.
fn refusal(text: &str) -> String {
    match EsiFile::parse(text) {
        Ok(f) => f
            .refused
            .first()
            .map_or_else(|| "loads".to_string(), |(_, e)| e.to_string()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn malformed_files_give_the_element_and_line() {
    let cases: [(&str, &str, &str); 6] = [
        (
            "ProductCode=\"#x07d43052\"",
            "ProductCode=\"#xZZ\"",
            "<Type> at line 8: bad ProductCode '#xZZ'",
        ),
        (
            "<BitLen>1</BitLen>",
            "<BitLen>300</BitLen>",
            "<BitLen> at line 17: bad BitLen '300'",
        ),
        (
            "Enable=\"1\" OpOnly=\"1\">Outputs",
            "Enable=\"1\">Sideways",
            "<Sm> at line 13: bad SyncManager type 'Sideways'",
        ),
        (
            "<Fmmu>Outputs</Fmmu>",
            "<Fmmu>Both</Fmmu>",
            "<Fmmu> at line 12: bad FMMU usage 'Both'",
        ),
        (
            "Sm=\"0\"",
            "Sm=\"3\"",
            "<RxPdo> at line 14: PDO 0x1600 is assigned to SM3, which is not described by an <Sm>",
        ),
        (
            "<ConfigData>0401000000000F00</ConfigData>",
            "<ConfigData>0401X</ConfigData>",
            "<ConfigData> at line 20: bad hexBinary '0401X'",
        ),
    ];
    for (from, to, want) in cases {
        let text = ONE.replace(from, to);
        assert_ne!(text, ONE, "{from}");
        assert_eq!(refusal(&text), want);
    }
    let tx = ONE.replace("<Sm StartAddress=\"#x0f00\"", "<Sm StartAddress=\"#x1000\" ControlByte=\"#x00\" Enable=\"1\">Inputs</Sm>\n<Sm StartAddress=\"#x0f00\"");
    // SM0 is now an input SM: an RxPDO on it is refused.
    let e = refusal(&tx);
    assert!(e.contains("not an output SyncManager"), "{e}");
    assert!(matches!(
        EsiFile::parse("<Other/>"),
        Err(EsiError::NotEsi(_))
    ));
    assert!(matches!(
        EsiFile::parse("<EtherCATInfo>"),
        Err(EsiError::Xml(_))
    ));
    let e = EsiFile::parse("<EtherCATInfo><Vendor><Id>2</Id></Vendor><Descriptions><Devices/></Descriptions></EtherCATInfo>").unwrap_err();
    assert!(e.to_string().contains("missing <Device>"), "{e}");
}

#[test]
fn mailbox_sms_smaller_than_one_sdo_are_refused() {
    let text = ONE.replace(
        "<Fmmu>Outputs</Fmmu>",
        "<Sm StartAddress=\"#x1000\" DefaultSize=\"8\" ControlByte=\"#x26\" Enable=\"1\">MBoxOut</Sm>",
    );
    let e = refusal(&text);
    assert!(
        e.contains("SM0 DefaultSize 8 bytes is too small for 16 bytes"),
        "{e}"
    );
}

#[test]
fn absurd_sm_addresses_and_eeprom_sizes_are_refused_at_load() {
    // A SyncManager running past the ESC's 64 KiB.
    let text = ONE.replace(
        "StartAddress=\"#x0f00\"",
        "StartAddress=\"#xfff0\" DefaultSize=\"256\"",
    );
    assert_eq!(
        refusal(&text),
        "<Sm> at line 13: SM0 at 0xfff0 with 256 bytes runs past the end of the ESC address space (0xffff)"
    );
    // Ending exactly at the top is fine.
    let top = ONE.replace(
        "StartAddress=\"#x0f00\"",
        "StartAddress=\"#xff00\" DefaultSize=\"256\"",
    );
    assert!(EsiFile::parse(&top).is_ok());
    // An EEPROM beyond the SII's 65535 kbit (ByteSize / 128).
    for (size, ok) in [("8388607", true), ("8388608", false), ("4294967295", false)] {
        let text = ONE.replace(
            "<ByteSize>2048</ByteSize>",
            &format!("<ByteSize>{size}</ByteSize>"),
        );
        match refusal(&text).as_str() {
            "loads" => assert!(ok, "{size}"),
            e => {
                assert!(!ok, "{size}: {e}");
                assert_eq!(
                    e,
                    format!(
                        "<ByteSize> at line 20: bad EEPROM ByteSize (at most 65535 kbit) '{size}'"
                    )
                );
            }
        }
    }
    let f = EsiFile::parse(ONE).unwrap();
    assert_eq!(f.devices[0].eeprom_kbit(), Some(16));
}

#[test]
fn base_type_names_map_to_coe_codes() {
    assert_eq!(base_type_code("BOOL"), Some(1));
    assert_eq!(base_type_code("BIT3"), Some(0x32));
    assert_eq!(base_type_code("BIT9"), None);
    assert_eq!(base_type_code("STRING(12)"), Some(9));
    assert_eq!(base_type_code("ULINT"), Some(0x1B));
    assert_eq!(base_type_code("FLOAT7"), None);
    assert_eq!(base_type_code("REAL"), Some(0x08));
    assert_eq!(base_type_code("BITARR16"), Some(0x2E));
    assert_eq!(base_type_code("ARRAY [0..27] OF BYTE"), Some(0x0A));
    assert_eq!(base_type_code("ARRAY [0..7] OF UINT"), Some(0x06));
    assert_eq!(array_bounds("ARRAY [0..-1] OF BYTE"), Some((0, -1)));
    assert_eq!(array_element("ARRAY[1..2]OF  INT"), Some("INT"));
    assert_eq!(array_element("ARRAY [0..1 OF BYTE"), None);
}

#[test]
fn one_refused_device_leaves_the_others_of_its_file() {
    let two = ONE.replace(
        "</Device>\n    </Devices>",
        "</Device>\n<Device><Type ProductCode=\"#xZZ\" RevisionNo=\"#x2\">EL9999</Type><Name>x</Name></Device>\n    </Devices>",
    );
    let f = EsiFile::parse(&two).unwrap();
    assert_eq!(f.devices.len(), 1);
    assert_eq!(f.refused.len(), 1);
    assert_eq!(f.refused[0].0, "EL9999 rev 0x00000002");
    let e = f.device(Some("EL9999"), None).unwrap_err().to_string();
    assert!(e.contains("bad ProductCode '#xZZ'"), "{e}");
}

#[test]
fn an_iso_8859_1_file_loads_with_lowercase_flags_and_its_names_decoded() {
    let latin1: Vec<u8> = ONE
        .replace(
            "<?xml version=\"1.0\"?>",
            "<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?>",
        )
        .replace("Deutsch", "Ausg\u{e4}nge")
        .chars()
        .map(|c| c as u8)
        .collect();
    assert!(latin1.contains(&0xE4));
    let f = EsiFile::parse_bytes(&latin1).unwrap();
    let de = f.devices[0].source.children_named("Name").next().unwrap();
    assert_eq!(de.text, "Ausg\u{e4}nge");
    assert!(
        EsiFile::parse_bytes(&latin1[..40]).is_err(),
        "cut: an error, no panic"
    );
}
