//! Sums of products in native `i128` digits: the fast exact path.
//!
//! Notation: a wide value `V` is written in base `2^64` as
//! `V = Σ_k v_k·2^(64k)`. A digit is *balanced* when `v_k ∈ [−2^63, 2^63)`
//! (any integer splits so), which keeps every product of two balanced
//! digits at most `2^126` in magnitude. The predicates group their partial
//! products by weight into digit sums `g_k`, each bounded (in the caller's
//! comments) below `2^127`, so they are exact in `i128`; one carry pass
//! then turns the digit sums into limbs or a sign. This keeps every
//! multiplication a single `64 × 64 → 128` instruction and every carry in
//! registers.

use super::sign::Sign;
use super::wide::Int;

/// `v = hi·2^64 + lo` with a balanced low digit `lo ∈ [−2^63, 2^63)`.
#[inline(always)]
pub(crate) fn split_balanced(v: i128) -> (i64, i128) {
    let lo = v as i64;
    (lo, (v - lo as i128) >> 64)
}

/// Balanced digits of a two's-complement value: `v = Σ d_k·2^(64k)` with
/// `d_k ∈ [−2^63, 2^63)` for `k < N − 1`. The top digit absorbs the last
/// carry, so it must have room: the caller's value is below `2^(64N − 2)`.
#[inline(always)]
pub(crate) fn to_balanced<const N: usize>(v: &Int<N>) -> [i64; N] {
    let limbs = v.limbs();
    let mut digits = [0i64; N];
    let mut carry = 0u64;
    for k in 0..N - 1 {
        // limb + carry may be 2^64, whose balanced digit is 0 with carry 1.
        let (t, overflow) = limbs[k].overflowing_add(carry);
        digits[k] = t as i64;
        carry = overflow as u64 + (t >> 63);
    }
    digits[N - 1] = (limbs[N - 1] as i64).wrapping_add(carry as i64);
    digits
}

/// `a·b` for 64-bit digits, exact.
#[inline(always)]
pub(crate) fn mul(a: i64, b: i64) -> i128 {
    a as i128 * b as i128
}

/// The limbs of `Σ g_k·2^(64k)` modulo `2^(64N)`; exact when the value fits
/// `N` limbs and each `g_k` plus an incoming carry (`|carry| < 2^64`) stays
/// inside `i128`.
#[inline(always)]
pub(crate) fn assemble<const N: usize>(g: [i128; N]) -> Int<N> {
    let mut limbs = [0u64; N];
    let mut carry = 0i128;
    for k in 0..N {
        let t = g[k] + carry;
        limbs[k] = t as u64;
        carry = t >> 64;
    }
    Int::from_limbs(limbs)
}

/// The sign of `Σ g_k·2^(64k)` (no wrap: the value is what it is), under
/// the same no-overflow condition as [`assemble`].
#[inline(always)]
pub(crate) fn sign_of_digits<const N: usize>(g: [i128; N]) -> Sign {
    let mut low_bits = 0u64;
    let mut carry = 0i128;
    for &digit in &g[..N - 1] {
        let t = digit + carry;
        low_bits |= t as u64;
        carry = t >> 64;
    }
    // Value = top·2^(64(N−1)) + L with 0 ≤ L < 2^(64(N−1)): the top digit
    // decides unless it is zero.
    let top = g[N - 1] + carry;
    if top != 0 {
        Sign::of_i128(top)
    } else if low_bits != 0 {
        Sign::Positive
    } else {
        Sign::Zero
    }
}
