/work/main/examples/firmware/target/release/deps/funty-2b800091706943bb.d: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/funty-2.0.0/src/lib.rs

/work/main/examples/firmware/target/release/deps/libfunty-2b800091706943bb.rlib: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/funty-2.0.0/src/lib.rs

/work/main/examples/firmware/target/release/deps/libfunty-2b800091706943bb.rmeta: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/funty-2.0.0/src/lib.rs

/root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/funty-2.0.0/src/lib.rs:
