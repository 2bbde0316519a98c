#![no_main]
//! See fuzz/README.md and `ilopt_fuzz::props::check_vo`.
use ilopt_fuzz::props::{VoInput, check_vo};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: VoInput| {
    check_vo(&input);
});
