//! The fixed-width integers against num-bigint: every operation is exact
//! modulo `2^(64·N)`, conversions round correctly, ordering and printing
//! agree.

use crate::common;

use chisel_bsp::exact::{I128, I192, I256, Int, Sign};
use common::backends::to_big;
use num_bigint::BigInt;
use num_traits::{Signed, ToPrimitive, Zero};
use proptest::prelude::*;

/// `v` reduced into the signed range of an `N`-limb integer.
fn wrap<const N: usize>(v: &BigInt) -> BigInt {
    let modulus = BigInt::from(1) << (64 * N);
    let half = BigInt::from(1) << (64 * N - 1);
    let mut r = ((v % &modulus) + &modulus) % &modulus;
    if r >= half {
        r -= modulus;
    }
    r
}

fn limbs<const N: usize>() -> impl Strategy<Value = Int<N>> {
    // Mix full-width limbs with sign-extended small values and extremes.
    prop_oneof![
        prop::array::uniform(any::<u64>()).prop_map(Int::from_limbs),
        any::<i64>().prop_map(Int::from_i64),
        any::<i128>().prop_map(Int::from_i128),
        Just(Int::from_limbs([u64::MAX; N])),
        Just({
            let mut l = [0u64; N];
            l[N - 1] = 1 << 63;
            Int::from_limbs(l)
        }),
    ]
}

/// True when `f` is a nearest `f64` to `v` (correct rounding, ties either way).
fn is_nearest(v: &BigInt, f: f64) -> bool {
    let exact_of = |x: f64| -> Option<BigInt> {
        if x.is_finite() {
            Some(float_to_big(x))
        } else {
            None
        }
    };
    let here = (v - exact_of(f).unwrap()).abs();
    let up = (v - exact_of(f.next_up()).unwrap()).abs();
    let down = (v - exact_of(f.next_down()).unwrap()).abs();
    here <= up && here <= down
}

/// Exact value of an integral or fractional `f64` truncated to an integer.
/// (Only integral values are compared here: `|v| ≥ 1` or `v = 0`.)
fn float_to_big(x: f64) -> BigInt {
    if x == 0.0 {
        return BigInt::zero();
    }
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i64;
    let mantissa = if exp == 0 {
        (bits & ((1 << 52) - 1)) << 1
    } else {
        (bits & ((1 << 52) - 1)) | (1 << 52)
    };
    let e = exp - 1075;
    let m = BigInt::from(mantissa);
    let mag = if e >= 0 {
        m << e as usize
    } else {
        m >> (-e) as usize
    };
    if x < 0.0 { -mag } else { mag }
}

macro_rules! width_suite {
    ($name:ident, $n:literal) => {
        mod $name {
            use super::*;
            type T = Int<$n>;
            proptest! {
                #![proptest_config(ProptestConfig::with_cases(2_000))]
                #[test]
                fn add_sub_neg_wrap_exactly(a in limbs::<$n>(), b in limbs::<$n>()) {
                    let (ba, bb) = (to_big(&a.limbs()), to_big(&b.limbs()));
                    prop_assert_eq!(to_big(&a.wrapping_add(&b).limbs()), wrap::<$n>(&(&ba + &bb)));
                    prop_assert_eq!(to_big(&a.wrapping_sub(&b).limbs()), wrap::<$n>(&(&ba - &bb)));
                    prop_assert_eq!(to_big(&a.wrapping_neg().limbs()), wrap::<$n>(&-&ba));
                }
                #[test]
                fn products_truncate_exactly(a in limbs::<$n>(), b in limbs::<$n>(), m in any::<i64>()) {
                    let (ba, bb) = (to_big(&a.limbs()), to_big(&b.limbs()));
                    let full: Int<{ 2 * $n }> = a.wrapping_mul(&b);
                    prop_assert_eq!(to_big(&full.limbs()), &ba * &bb);
                    let same: T = a.wrapping_mul(&b);
                    prop_assert_eq!(to_big(&same.limbs()), wrap::<$n>(&(&ba * &bb)));
                    let wide: Int<4> = a.wrapping_mul(&b);
                    prop_assert_eq!(to_big(&wide.limbs()), wrap::<4>(&(&ba * &bb)));
                    prop_assert_eq!(to_big(&a.wrapping_mul_i64(m).limbs()), wrap::<$n>(&(&ba * m)));
                }
                #[test]
                fn sign_order_and_display_agree(a in limbs::<$n>(), b in limbs::<$n>()) {
                    let (ba, bb) = (to_big(&a.limbs()), to_big(&b.limbs()));
                    prop_assert_eq!(a.cmp(&b), ba.cmp(&bb));
                    let expected = if ba.is_zero() { Sign::Zero } else if ba.is_positive() { Sign::Positive } else { Sign::Negative };
                    prop_assert_eq!(a.sign(), expected);
                    prop_assert_eq!(a.to_string(), ba.to_string());
                    prop_assert_eq!(a.magnitude_bits() as u64, ba.bits());
                    prop_assert_eq!(a.to_i128(), ba.to_i128());
                }
                #[test]
                fn to_f64_rounds_to_nearest(a in limbs::<$n>()) {
                    let ba = to_big(&a.limbs());
                    prop_assert!(is_nearest(&ba, a.to_f64()), "{} -> {}", ba, a.to_f64());
                }
                #[test]
                fn resize_sign_extends_and_truncates(a in limbs::<$n>()) {
                    let ba = to_big(&a.limbs());
                    let up: Int<6> = a.resize();
                    prop_assert_eq!(to_big(&up.limbs()), ba.clone());
                    let down: Int<1> = a.resize();
                    prop_assert_eq!(to_big(&down.limbs()), wrap::<1>(&ba));
                }
            }
        }
    };
}

width_suite!(i128_limbs, 2);
width_suite!(i192_limbs, 3);
width_suite!(i256_limbs, 4);

#[test]
fn aliases_have_the_documented_widths() {
    assert_eq!(I128::BITS, 128);
    assert_eq!(I192::BITS, 192);
    assert_eq!(I256::BITS, 256);
}

#[test]
fn to_f64_rounds_halfway_cases_to_even() {
    // 2^53 + 1 is halfway between 2^53 and 2^53 + 2: ties to even gives 2^53.
    let v = I256::from_i128((1i128 << 53) + 1);
    assert_eq!(v.to_f64(), 9007199254740992.0);
    // Above 64 bits the sticky bit must break the tie upwards: 2^70 + 2^17 + 1.
    let v = I256::from_i128((1i128 << 70) + (1 << 17) + 1);
    assert_eq!(v.to_f64(), (1u128 << 70) as f64 + (1u64 << 18) as f64);
    // Exactly halfway above 64 bits rounds to even (down here).
    let v = I256::from_i128((1i128 << 70) + (1 << 17));
    assert_eq!(v.to_f64(), (1u128 << 70) as f64);
    assert_eq!(I256::from_i64(-3).to_f64(), -3.0);
    assert_eq!(I256::ZERO.to_f64(), 0.0);
}
