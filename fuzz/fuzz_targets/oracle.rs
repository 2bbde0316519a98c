#![no_main]
//! See fuzz/README.md and `ilopt_fuzz::props::check_oracle`.
use ilopt_fuzz::props::{OracleInput, check_oracle};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: OracleInput| {
    check_oracle(&input);
});
