//! Shared code of the fuzz targets: the properties ([`props`], also used by the crate's
//! `cargo test` suites) and `arbitrary` impls for their inputs.

pub mod props;

use arbitrary::{Arbitrary, Result, Unstructured};
use props::{CartpoleInput, Frac, MdpSpec, OracleInput, TrajSpec, VoInput};

fn small_vec<'a, T>(
    u: &mut Unstructured<'a>,
    max: usize,
    mut f: impl FnMut(&mut Unstructured<'a>) -> Result<T>,
) -> Result<Vec<T>> {
    let n = u.int_in_range(0..=max)?;
    (0..n).map(|_| f(u)).collect()
}

fn frac(u: &mut Unstructured<'_>) -> Result<Frac> {
    // Mostly tiny numbers (fast rationals); sometimes the full i16 range.
    let num = if u.ratio(1, 8)? {
        i16::arbitrary(u)?
    } else {
        i16::from(u.int_in_range(-8i8..=8)?)
    };
    let den = if u.ratio(1, 8)? {
        u8::arbitrary(u)?
    } else {
        u.int_in_range(1u8..=8)?
    };
    Ok(Frac { num, den })
}

impl<'a> Arbitrary<'a> for MdpSpec {
    fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
        // Mostly valid sizes (S ≤ 3, 2 ≤ A ≤ 3, 2 ≤ T ≤ 4), sometimes invalid ones.
        let states = if u.ratio(1, 16)? {
            0
        } else {
            u.int_in_range(1..=3)?
        };
        let actions = if u.ratio(1, 16)? {
            1
        } else {
            u.int_in_range(2..=3)?
        };
        let horizon = if u.ratio(1, 16)? {
            1
        } else {
            u.int_in_range(2..=4)?
        };
        Ok(MdpSpec {
            states,
            actions,
            horizon,
            probs: small_vec(u, 12, frac)?,
            normalize: u.ratio(7, 8)?,
            expert: small_vec(u, 3, |u| {
                // Mostly valid for every A ≥ 2; sometimes A itself (rejected).
                if u.ratio(1, 16)? {
                    u.int_in_range(0..=3)
                } else {
                    u.int_in_range(0..=1)
                }
            })?,
            kind: u.int_in_range(0..=3)?,
            c: {
                // Mostly a valid c > 0 (a non-positive c only tests one error path).
                let f = frac(u)?;
                if u.ratio(7, 8)? {
                    Frac {
                        num: f.num.saturating_abs().max(1),
                        den: f.den.max(1),
                    }
                } else {
                    f
                }
            },
            groups: if u.ratio(1, 4)? {
                Some(small_vec(u, 3, |u| u.int_in_range(0..=3))?)
            } else {
                None
            },
        })
    }
}

impl<'a> Arbitrary<'a> for TrajSpec {
    fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
        let b = |u: &mut Unstructured<'a>| -> Result<u8> {
            if u.ratio(1, 16)? {
                u8::arbitrary(u)
            } else {
                u.int_in_range(0..=3)
            }
        };
        Ok(TrajSpec {
            states: small_vec(u, 5, b)?,
            actions: small_vec(u, 5, b)?,
            labels: small_vec(u, 5, b)?,
            conform: u.ratio(7, 8)?,
        })
    }
}

impl<'a> Arbitrary<'a> for OracleInput {
    fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
        Ok(OracleInput {
            mdp: MdpSpec::arbitrary(u)?,
            theta: small_vec(u, 9, frac)?,
            theta_new: small_vec(u, 9, frac)?,
            fit_theta: u.ratio(7, 8)?,
            traj: TrajSpec::arbitrary(u)?,
            seed: u64::arbitrary(u)?,
            expert_weight: if u.ratio(3, 4)? {
                f64::from(u.int_in_range(0u8..=4)?) / 4.0
            } else {
                f64::arbitrary(u)?
            },
        })
    }
}

/// A float that is usually "interesting": small integers and halves, the special values, or raw
/// bits.
pub fn any_f64(u: &mut Unstructured<'_>) -> Result<f64> {
    Ok(match u.int_in_range(0u8..=7)? {
        0 | 1 => f64::arbitrary(u)?,
        2 => *u.choose(&[
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            f64::MAX,
            f64::MIN,
            1e150,
            1e-300,
            f64::EPSILON,
        ])?,
        _ => f64::from(i16::arbitrary(u)?) / f64::from(u.int_in_range(1u8..=16)?),
    })
}

impl<'a> Arbitrary<'a> for VoInput {
    fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
        let mut v = [0.0; 12];
        for x in &mut v {
            *x = any_f64(u)?;
        }
        Ok(VoInput {
            r: [v[0], v[1]],
            v_o: [v[2], v[3]],
            v_r: [v[4], v[5]],
            v_des: [v[6], v[7]],
            lam: v[8],
            big_r: v[9],
            probes: [v[10], v[11]],
        })
    }
}

impl<'a> Arbitrary<'a> for CartpoleInput {
    fn arbitrary(u: &mut Unstructured<'a>) -> Result<Self> {
        let mut init = [0.0; 4];
        for x in &mut init {
            *x = any_f64(u)?;
        }
        Ok(CartpoleInput {
            init,
            actions: small_vec(u, 64, |u| {
                if u.ratio(1, 32)? {
                    u8::arbitrary(u)
                } else {
                    u.int_in_range(0..=1)
                }
            })?,
            text: String::arbitrary(u)?,
        })
    }
}
