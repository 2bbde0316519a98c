//! Regression tests for what the fuzz targets (`fuzz/`) found: each crashing input is
//! inlined and run through the target's own property (`fuzz/src/props/`), with a note on the
//! cause and the fix. A target's seed corpus is replayed here too, so `cargo test` covers it.

use crate::props;

use crate::props::{CartpoleInput, VoInput};

fn corpus(target: &str) -> Vec<Vec<u8>> {
    let dir = format!("{}/fuzz/corpus/{target}", env!("CARGO_MANIFEST_DIR"));
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    files.iter().map(|p| std::fs::read(p).unwrap()).collect()
}

#[test]
fn toy_parser_seed_corpus() {
    for bytes in corpus("toy_parser") {
        props::check_toy_parser(&bytes);
    }
}

#[test]
fn config_seed_corpus() {
    for bytes in corpus("config") {
        props::check_config(&bytes);
    }
}

#[test]
fn vo_expert_hand_picked_geometry() {
    // Dead ahead (the module's worked example), huge and tiny inputs, NaN.
    for (r, v_des, big_r) in [
        ([1.0, 0.0], [1.0, 0.0], 0.5),
        ([1e150, 0.0], [1e150, 1.0], 1e149),
        ([1e-300, 0.0], [1.0, 0.0], 1e-301),
        ([f64::NAN, 0.0], [1.0, 0.0], 0.5),
    ] {
        props::check_vo(&VoInput {
            r,
            v_o: [0.0, 0.0],
            v_r: [0.0, 0.0],
            v_des,
            lam: 0.0,
            big_r,
            probes: [1.0, -3.0],
        });
    }
}

#[test]
fn cartpole_hand_picked_states() {
    for init in [
        [0.0, 0.0, 0.0, 0.0],
        [2.4, 0.0, 0.0, 0.0],
        [0.0, 0.0, 0.209_439_510_239_319_53, 0.0],
        [0.0, 0.0, 0.0, 1e200],
        [f64::NAN, 0.0, 0.0, 0.0],
    ] {
        props::check_cartpole(&CartpoleInput {
            init,
            actions: vec![0, 1, 1, 7, 0],
            text: "0,1,x".into(),
        });
    }
}

/// `vo_expert` target, crash-275aa4c8: ‖r‖, R and the velocities ≈ 6e−154. The feasibility test
/// `(rᵀw)² > (‖r‖² − R²)‖w‖²` underflowed to `0 > 0`, so the unconstrained minimiser u₀ was
/// returned although it lies inside the collision cone. Fixed in `src/expert/vo.rs`
/// (`vo_expert_cone`): inputs below 2⁻⁶⁰ are rescaled by exact powers of two, the geometry (r, R)
/// and the velocities separately.
#[test]
fn vo_expert_tiny_inputs_underflow() {
    let t = 6.013_470_016_999_068e-154;
    props::check_vo(&VoInput {
        r: [1.270_191_886_756_896_2e-299, 6.013_472_915_405_47e-154],
        v_o: [t, t],
        v_r: [t, t],
        v_des: [t, 2.097_694_891_143_838_5e-153],
        lam: t,
        big_r: t,
        probes: [-7.640_966_620_460_772e-142, 1e150],
    });
}

/// `vo_expert` target, crash-35f91006: not a library bug — the property's own tolerance
/// overflowed (‖r‖ ≈ 2e147 with R ≈ 6e−317 makes the slack infinite) and the exact check then
/// converted ∞ to a rational. The property now treats an infinite slack as "no information".
#[test]
fn vo_expert_infinite_slack() {
    props::check_vo(&VoInput {
        r: [1.396_755_974_046_524_5e-304, 2.132_170_128_426_316_5e147],
        v_o: [1_610.533_333_333_333_3, 1_509.875],
        v_r: [3.792_128_748_738_515e146, 2.442_566_542_453_456_8e-85],
        v_des: [1_606.666_666_666_666_7, 1_610.533_333_333_333_3],
        lam: 0.0,
        big_r: 5.698_719e-317,
        probes: [0.0, 0.0],
    });
}

/// `vo_expert` target, crash-e32e7623: not a library bug — with ‖r‖ ≈ 2e−276 and R subnormal the
/// property's absolute tolerance `64ε(‖r‖² + R²)(…)` underflowed to 0·∞ = NaN. The tolerance is
/// now relative to `‖r‖² + R²` and applied exactly (scale-invariant, as is the library's
/// rescaling); the library's answer here is feasible.
#[test]
fn vo_expert_tiny_geometry_huge_velocity() {
    props::check_vo(&VoInput {
        r: [6.527_671_473_216_822e-293, -1.957_483_972_527_704e-276],
        v_o: [8_302.0, 9.434_266_880_855_467e-136],
        v_r: [-3.896_155_832_256_809e117, -721.181_818_181_818_1],
        v_des: [-1_123.0, -0.0],
        lam: 5.569_147e-318,
        big_r: 2.815_769_747_954_16e-310,
        probes: [0.0, 0.0],
    });
}

/// `vo_expert` target, crash-75a69ce6: not a library bug — v_o is subnormal (6.5e−319), so the
/// optimum u* is subnormal too and has only a few significant bits; no float is closer to the
/// cone's boundary. The property's position error now includes the subnormal spacing 2⁻¹⁰⁷⁴.
#[test]
fn vo_expert_subnormal_solution() {
    props::check_vo(&VoInput {
        r: [0.0, 6.627_417_254_342_74e-310],
        v_o: [0.0, 6.4758e-319],
        v_r: [0.0, 0.0],
        v_des: [0.0, 0.0],
        lam: 0.0,
        big_r: 4.617_462_841_140_43e-310,
        probes: [0.0, 0.0],
    });
}

/// `vo_expert` target, crash-(r = (1.1e−308, 1e−300), R = 1e−300): not a library bug — ‖r‖
/// exceeds R by less than an ulp (‖r‖² − R² ≈ 1.2e−616), so the library is right to solve it
/// (after its rescaling); the property compared `hypot(r) > R` in floats, which rounds to
/// equality. It now decides ‖r‖ > R exactly.
#[test]
fn vo_expert_outside_by_less_than_an_ulp() {
    props::check_vo(&VoInput {
        r: [1.112_596_345_135_747_7e-308, 1e-300],
        v_o: [1e-300, 1e-300],
        v_r: [1e150, 1e-300],
        v_des: [1e-300, 1e-300],
        lam: 1e-300,
        big_r: 1e-300,
        probes: [0.0, 0.0],
    });
}
