#![no_main]
//! See fuzz/README.md and `ilopt_fuzz::props::check_differential`.
use ilopt_fuzz::props::{OracleInput, check_differential};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: OracleInput| {
    check_differential(&input);
});
