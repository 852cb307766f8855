/work/main/examples/firmware/target/release/deps/ecat_firmware-f16d69148889926e.d: src/lib.rs src/board.rs src/cell.rs src/ffi.rs

/work/main/examples/firmware/target/release/deps/libecat_firmware-f16d69148889926e.a: src/lib.rs src/board.rs src/cell.rs src/ffi.rs

src/lib.rs:
src/board.rs:
src/cell.rs:
src/ffi.rs:
