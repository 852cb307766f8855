/work/main/examples/firmware/target/release/deps/ecat_slave-a4aee02878d3c256.d: /work/main/slave/src/lib.rs /work/main/slave/src/al.rs /work/main/slave/src/coe/mod.rs /work/main/slave/src/coe/emergency.rs /work/main/slave/src/coe/sdo.rs /work/main/slave/src/coe/sdo_info.rs /work/main/slave/src/device/mod.rs /work/main/slave/src/device/application.rs /work/main/slave/src/device/description.rs /work/main/slave/src/device/schedule.rs /work/main/slave/src/device/sii_image.rs /work/main/slave/src/device/slave.rs /work/main/slave/src/esc/mod.rs /work/main/slave/src/firmware/mod.rs /work/main/slave/src/firmware/boot.rs /work/main/slave/src/firmware/efw.rs /work/main/slave/src/firmware/store.rs /work/main/slave/src/foe.rs /work/main/slave/src/hal.rs /work/main/slave/src/led.rs /work/main/slave/src/limits.rs /work/main/slave/src/mailbox.rs /work/main/slave/src/od/mod.rs /work/main/slave/src/od/bits.rs /work/main/slave/src/od/build.rs /work/main/slave/src/od/complete.rs /work/main/slave/src/od/dictionary.rs /work/main/slave/src/od/modules.rs /work/main/slave/src/od/store.rs /work/main/slave/src/od/sub_names.rs /work/main/slave/src/od/types.rs /work/main/slave/src/params.rs /work/main/slave/src/pdo.rs /work/main/slave/src/sii/mod.rs /work/main/slave/src/sii/crc.rs /work/main/slave/src/sii/encode.rs /work/main/slave/src/sii/read.rs /work/main/slave/src/wire/mod.rs /work/main/slave/src/wire/builder.rs /work/main/slave/src/wire/coe/mod.rs /work/main/slave/src/wire/coe/abort.rs /work/main/slave/src/wire/coe/emergency.rs /work/main/slave/src/wire/coe/header.rs /work/main/slave/src/wire/coe/sdo.rs /work/main/slave/src/wire/coe/sdo_info.rs /work/main/slave/src/wire/coe/sdo_repr.rs /work/main/slave/src/wire/ecat.rs /work/main/slave/src/wire/ethernet.rs /work/main/slave/src/wire/foe.rs /work/main/slave/src/wire/mailbox.rs

/work/main/examples/firmware/target/release/deps/libecat_slave-a4aee02878d3c256.rlib: /work/main/slave/src/lib.rs /work/main/slave/src/al.rs /work/main/slave/src/coe/mod.rs /work/main/slave/src/coe/emergency.rs /work/main/slave/src/coe/sdo.rs /work/main/slave/src/coe/sdo_info.rs /work/main/slave/src/device/mod.rs /work/main/slave/src/device/application.rs /work/main/slave/src/device/description.rs /work/main/slave/src/device/schedule.rs /work/main/slave/src/device/sii_image.rs /work/main/slave/src/device/slave.rs /work/main/slave/src/esc/mod.rs /work/main/slave/src/firmware/mod.rs /work/main/slave/src/firmware/boot.rs /work/main/slave/src/firmware/efw.rs /work/main/slave/src/firmware/store.rs /work/main/slave/src/foe.rs /work/main/slave/src/hal.rs /work/main/slave/src/led.rs /work/main/slave/src/limits.rs /work/main/slave/src/mailbox.rs /work/main/slave/src/od/mod.rs /work/main/slave/src/od/bits.rs /work/main/slave/src/od/build.rs /work/main/slave/src/od/complete.rs /work/main/slave/src/od/dictionary.rs /work/main/slave/src/od/modules.rs /work/main/slave/src/od/store.rs /work/main/slave/src/od/sub_names.rs /work/main/slave/src/od/types.rs /work/main/slave/src/params.rs /work/main/slave/src/pdo.rs /work/main/slave/src/sii/mod.rs /work/main/slave/src/sii/crc.rs /work/main/slave/src/sii/encode.rs /work/main/slave/src/sii/read.rs /work/main/slave/src/wire/mod.rs /work/main/slave/src/wire/builder.rs /work/main/slave/src/wire/coe/mod.rs /work/main/slave/src/wire/coe/abort.rs /work/main/slave/src/wire/coe/emergency.rs /work/main/slave/src/wire/coe/header.rs /work/main/slave/src/wire/coe/sdo.rs /work/main/slave/src/wire/coe/sdo_info.rs /work/main/slave/src/wire/coe/sdo_repr.rs /work/main/slave/src/wire/ecat.rs /work/main/slave/src/wire/ethernet.rs /work/main/slave/src/wire/foe.rs /work/main/slave/src/wire/mailbox.rs

/work/main/examples/firmware/target/release/deps/libecat_slave-a4aee02878d3c256.rmeta: /work/main/slave/src/lib.rs /work/main/slave/src/al.rs /work/main/slave/src/coe/mod.rs /work/main/slave/src/coe/emergency.rs /work/main/slave/src/coe/sdo.rs /work/main/slave/src/coe/sdo_info.rs /work/main/slave/src/device/mod.rs /work/main/slave/src/device/application.rs /work/main/slave/src/device/description.rs /work/main/slave/src/device/schedule.rs /work/main/slave/src/device/sii_image.rs /work/main/slave/src/device/slave.rs /work/main/slave/src/esc/mod.rs /work/main/slave/src/firmware/mod.rs /work/main/slave/src/firmware/boot.rs /work/main/slave/src/firmware/efw.rs /work/main/slave/src/firmware/store.rs /work/main/slave/src/foe.rs /work/main/slave/src/hal.rs /work/main/slave/src/led.rs /work/main/slave/src/limits.rs /work/main/slave/src/mailbox.rs /work/main/slave/src/od/mod.rs /work/main/slave/src/od/bits.rs /work/main/slave/src/od/build.rs /work/main/slave/src/od/complete.rs /work/main/slave/src/od/dictionary.rs /work/main/slave/src/od/modules.rs /work/main/slave/src/od/store.rs /work/main/slave/src/od/sub_names.rs /work/main/slave/src/od/types.rs /work/main/slave/src/params.rs /work/main/slave/src/pdo.rs /work/main/slave/src/sii/mod.rs /work/main/slave/src/sii/crc.rs /work/main/slave/src/sii/encode.rs /work/main/slave/src/sii/read.rs /work/main/slave/src/wire/mod.rs /work/main/slave/src/wire/builder.rs /work/main/slave/src/wire/coe/mod.rs /work/main/slave/src/wire/coe/abort.rs /work/main/slave/src/wire/coe/emergency.rs /work/main/slave/src/wire/coe/header.rs /work/main/slave/src/wire/coe/sdo.rs /work/main/slave/src/wire/coe/sdo_info.rs /work/main/slave/src/wire/coe/sdo_repr.rs /work/main/slave/src/wire/ecat.rs /work/main/slave/src/wire/ethernet.rs /work/main/slave/src/wire/foe.rs /work/main/slave/src/wire/mailbox.rs

/work/main/slave/src/lib.rs:
/work/main/slave/src/al.rs:
/work/main/slave/src/coe/mod.rs:
/work/main/slave/src/coe/emergency.rs:
/work/main/slave/src/coe/sdo.rs:
/work/main/slave/src/coe/sdo_info.rs:
/work/main/slave/src/device/mod.rs:
/work/main/slave/src/device/application.rs:
/work/main/slave/src/device/description.rs:
/work/main/slave/src/device/schedule.rs:
/work/main/slave/src/device/sii_image.rs:
/work/main/slave/src/device/slave.rs:
/work/main/slave/src/esc/mod.rs:
/work/main/slave/src/firmware/mod.rs:
/work/main/slave/src/firmware/boot.rs:
/work/main/slave/src/firmware/efw.rs:
/work/main/slave/src/firmware/store.rs:
/work/main/slave/src/foe.rs:
/work/main/slave/src/hal.rs:
/work/main/slave/src/led.rs:
/work/main/slave/src/limits.rs:
/work/main/slave/src/mailbox.rs:
/work/main/slave/src/od/mod.rs:
/work/main/slave/src/od/bits.rs:
/work/main/slave/src/od/build.rs:
/work/main/slave/src/od/complete.rs:
/work/main/slave/src/od/dictionary.rs:
/work/main/slave/src/od/modules.rs:
/work/main/slave/src/od/store.rs:
/work/main/slave/src/od/sub_names.rs:
/work/main/slave/src/od/types.rs:
/work/main/slave/src/params.rs:
/work/main/slave/src/pdo.rs:
/work/main/slave/src/sii/mod.rs:
/work/main/slave/src/sii/crc.rs:
/work/main/slave/src/sii/encode.rs:
/work/main/slave/src/sii/read.rs:
/work/main/slave/src/wire/mod.rs:
/work/main/slave/src/wire/builder.rs:
/work/main/slave/src/wire/coe/mod.rs:
/work/main/slave/src/wire/coe/abort.rs:
/work/main/slave/src/wire/coe/emergency.rs:
/work/main/slave/src/wire/coe/header.rs:
/work/main/slave/src/wire/coe/sdo.rs:
/work/main/slave/src/wire/coe/sdo_info.rs:
/work/main/slave/src/wire/coe/sdo_repr.rs:
/work/main/slave/src/wire/ecat.rs:
/work/main/slave/src/wire/ethernet.rs:
/work/main/slave/src/wire/foe.rs:
/work/main/slave/src/wire/mailbox.rs:
