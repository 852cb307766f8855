/work/main/examples/firmware/target/release/deps/io8_example-4cfefb0608589517.d: /work/main/examples/io8/src/lib.rs /work/main/examples/io8/src/app.rs /work/main/examples/io8/src/board.rs /work/main/examples/io8/src/description.rs /work/main/examples/io8/src/../WRITE-YOUR-OWN-DEVICE.md

/work/main/examples/firmware/target/release/deps/libio8_example-4cfefb0608589517.rlib: /work/main/examples/io8/src/lib.rs /work/main/examples/io8/src/app.rs /work/main/examples/io8/src/board.rs /work/main/examples/io8/src/description.rs /work/main/examples/io8/src/../WRITE-YOUR-OWN-DEVICE.md

/work/main/examples/firmware/target/release/deps/libio8_example-4cfefb0608589517.rmeta: /work/main/examples/io8/src/lib.rs /work/main/examples/io8/src/app.rs /work/main/examples/io8/src/board.rs /work/main/examples/io8/src/description.rs /work/main/examples/io8/src/../WRITE-YOUR-OWN-DEVICE.md

/work/main/examples/io8/src/lib.rs:
/work/main/examples/io8/src/app.rs:
/work/main/examples/io8/src/board.rs:
/work/main/examples/io8/src/description.rs:
/work/main/examples/io8/src/../WRITE-YOUR-OWN-DEVICE.md:
