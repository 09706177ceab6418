//! Tests of the `raykin` binary (`CARGO_BIN_EXE_raykin`): the commands end to end, their errors and outputs,
//! and the viewer (offscreen and under Xvfb). One integration-test binary, one module per command.
//!   cargo test --workspace --test cli -- record::      (one module)

#[path = "../common/mod.rs"]
mod common;

mod bad_input;
mod bench;
mod cli_args;
mod denoise;
mod oidn;
mod record;
mod validation;
mod viewer;
