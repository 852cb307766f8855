/work/main/examples/firmware/target/release/deps/radium-5a9fada81cbebdc0.d: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/lib.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/macros.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/types.rs

/work/main/examples/firmware/target/release/deps/libradium-5a9fada81cbebdc0.rlib: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/lib.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/macros.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/types.rs

/work/main/examples/firmware/target/release/deps/libradium-5a9fada81cbebdc0.rmeta: /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/lib.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/macros.rs /root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/types.rs

/root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/lib.rs:
/root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/macros.rs:
/root/.cargo/registry/src/index.crates.io-1949cf8c6b5b557f/radium-0.7.0/src/types.rs:
