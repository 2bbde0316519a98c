#![no_main]
//! See fuzz/README.md and `ilopt_fuzz::props::check_cartpole`.
use ilopt_fuzz::props::{CartpoleInput, check_cartpole};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|input: CartpoleInput| {
    check_cartpole(&input);
});
