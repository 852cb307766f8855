/work/main/examples/firmware/target/release/deps/ecat_pdi-8826e37d5709dffd.d: /work/main/drivers/pdi/src/lib.rs /work/main/drivers/pdi/src/registers.rs

/work/main/examples/firmware/target/release/deps/libecat_pdi-8826e37d5709dffd.rlib: /work/main/drivers/pdi/src/lib.rs /work/main/drivers/pdi/src/registers.rs

/work/main/examples/firmware/target/release/deps/libecat_pdi-8826e37d5709dffd.rmeta: /work/main/drivers/pdi/src/lib.rs /work/main/drivers/pdi/src/registers.rs

/work/main/drivers/pdi/src/lib.rs:
/work/main/drivers/pdi/src/registers.rs:
