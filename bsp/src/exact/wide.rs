//! Fixed-width signed integers over 64-bit limbs (paper 1 §3.2).
//!
//! `Int<N>` is an `N × 64`-bit two's-complement integer stored as little-endian
//! `u64` limbs. All arithmetic is *wrapping*, i.e. exact modulo `2^(64·N)`.
//! That is the point: the predicates in this crate are sums of products whose
//! final value is proven (by the bounds in [`super::budget`]) to fit in the
//! signed range of the result type, so every intermediate carry or overflow
//! cancels and the final bits are exact. Products are truncated to the limbs
//! the result needs, so no limb product above them is ever computed.
//!
//! Notation: `N`, `K` — operand limb counts; `M` — result limb count;
//! `limb[i]` has weight `2^(64·i)`.

use core::cmp::Ordering;
use core::fmt;

use super::sign::Sign;

/// An `N × 64`-bit two's-complement signed integer (little-endian limbs).
///
/// Arithmetic wraps modulo `2^(64·N)`; callers choose `N` from the proven
/// bit budget of the quantity so that results never actually wrap.
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Int<const N: usize>(pub(crate) [u64; N]);

/// 64-bit signed integer as one limb (an operand of mixed-width products).
pub type I64 = Int<1>;
/// 128-bit signed integer over two limbs.
pub type I128 = Int<2>;
/// 192-bit signed integer over three limbs.
pub type I192 = Int<3>;
/// 256-bit signed integer over four limbs.
pub type I256 = Int<4>;

impl<const N: usize> Int<N> {
    /// Number of bits, `64 · N`.
    pub const BITS: u32 = 64 * N as u32;
    /// Zero.
    pub const ZERO: Self = Self([0; N]);

    /// Builds from little-endian two's-complement limbs.
    #[must_use]
    pub const fn from_limbs(limbs: [u64; N]) -> Self {
        Self(limbs)
    }

    /// The little-endian two's-complement limbs.
    #[must_use]
    pub const fn limbs(&self) -> [u64; N] {
        self.0
    }

    /// Sign-extends (or, for `N ≤ 2`, wraps) an `i128`.
    #[must_use]
    #[inline]
    pub fn from_i128(v: i128) -> Self {
        let fill = if v < 0 { u64::MAX } else { 0 };
        let mut limbs = [fill; N];
        let u = v as u128;
        if N > 0 {
            limbs[0] = u as u64;
        }
        if N > 1 {
            limbs[1] = (u >> 64) as u64;
        }
        Self(limbs)
    }

    /// Sign-extends an `i64`.
    #[must_use]
    #[inline]
    pub fn from_i64(v: i64) -> Self {
        Self::from_i128(v as i128)
    }

    /// Converts to `i128` when the value fits, `None` otherwise.
    #[must_use]
    pub fn to_i128(&self) -> Option<i128> {
        let lo = if N > 0 { self.0[0] } else { 0 };
        let hi = if N > 1 { self.0[1] } else { 0 };
        let v = ((hi as u128) << 64 | lo as u128) as i128;
        let fill = if v < 0 { u64::MAX } else { 0 };
        self.0.iter().skip(2).all(|&l| l == fill).then_some(v)
    }

    /// Sign extension (`M ≥ N`) or truncation modulo `2^(64·M)` (`M < N`).
    #[must_use]
    #[inline]
    pub fn resize<const M: usize>(&self) -> Int<M> {
        let fill = if self.is_negative() { u64::MAX } else { 0 };
        let mut out = [fill; M];
        let n = if M < N { M } else { N };
        out[..n].copy_from_slice(&self.0[..n]);
        Int(out)
    }

    /// True when the value is below zero.
    #[must_use]
    #[inline]
    pub fn is_negative(&self) -> bool {
        N > 0 && (self.0[N - 1] as i64) < 0
    }

    /// True when the value is zero.
    #[must_use]
    #[inline]
    pub fn is_zero(&self) -> bool {
        self.0.iter().all(|&l| l == 0)
    }

    /// The sign of the value.
    #[must_use]
    #[inline]
    pub fn sign(&self) -> Sign {
        if self.is_negative() {
            Sign::Negative
        } else if self.is_zero() {
            Sign::Zero
        } else {
            Sign::Positive
        }
    }

    /// `self + rhs` modulo `2^(64·N)`.
    #[must_use]
    #[inline]
    pub fn wrapping_add(&self, rhs: &Self) -> Self {
        let mut out = [0u64; N];
        let mut carry = false;
        for (i, o) in out.iter_mut().enumerate() {
            let (s1, c1) = self.0[i].overflowing_add(rhs.0[i]);
            let (s2, c2) = s1.overflowing_add(carry as u64);
            *o = s2;
            carry = c1 | c2;
        }
        Self(out)
    }

    /// `self − rhs` modulo `2^(64·N)`.
    #[must_use]
    #[inline]
    pub fn wrapping_sub(&self, rhs: &Self) -> Self {
        let mut out = [0u64; N];
        let mut borrow = false;
        for (i, o) in out.iter_mut().enumerate() {
            let (s1, b1) = self.0[i].overflowing_sub(rhs.0[i]);
            let (s2, b2) = s1.overflowing_sub(borrow as u64);
            *o = s2;
            borrow = b1 | b2;
        }
        Self(out)
    }

    /// `−self` modulo `2^(64·N)`.
    #[must_use]
    #[inline]
    pub fn wrapping_neg(&self) -> Self {
        Self::ZERO.wrapping_sub(self)
    }

    /// `−self` when `negate`, else `self`.
    #[must_use]
    #[inline]
    pub fn negate_if(&self, negate: bool) -> Self {
        if negate { self.wrapping_neg() } else { *self }
    }

    /// Magnitude limbs (`|self|` as an unsigned `N`-limb number; exact even
    /// for the most negative value) and whether `self` was negative.
    #[must_use]
    #[inline]
    pub fn unsigned_abs(&self) -> ([u64; N], bool) {
        let neg = self.is_negative();
        (if neg { self.wrapping_neg().0 } else { self.0 }, neg)
    }

    /// `self × m` modulo `2^(64·N)` for a small signed factor.
    #[must_use]
    #[inline]
    pub fn wrapping_mul_i64(&self, m: i64) -> Self {
        let mut out = Self::ZERO;
        out.add_product(self, &I64::from_i64(m));
        out
    }

    /// The product `self × rhs` truncated to `M` limbs (exact modulo
    /// `2^(64·M)`).
    #[must_use]
    #[inline]
    pub fn wrapping_mul<const K: usize, const M: usize>(&self, rhs: &Int<K>) -> Int<M> {
        let mut out = Int::<M>::ZERO;
        out.add_product(self, rhs);
        out
    }

    /// `self += a × b` modulo `2^(64·N)`: the multiply–accumulate step of
    /// every predicate.
    ///
    /// Works on the two's-complement limbs directly. Reading `a` and `b` as
    /// unsigned (`a_u = a + 2^(64A)·[a < 0]`, likewise `b_u`),
    ///
    /// ```text
    ///     a·b = a_u·b_u − [a < 0]·2^(64A)·b_u − [b < 0]·2^(64B)·a_u   (mod 2^(64N))
    /// ```
    ///
    /// whenever `A + B ≥ N` (the `2^(64(A+B))` term vanishes), which holds
    /// for every use in the kernel and is checked at compile time. The
    /// unsigned product computes only limb pairs `i + j < N`, and the top
    /// one only to 64 bits; the corrections are branch-free masked
    /// subtractions.
    #[inline]
    pub fn add_product<const A: usize, const B: usize>(&mut self, a: &Int<A>, b: &Int<B>) {
        const { assert!(A + B >= N, "add_product needs A + B >= N") };
        let acc = &mut self.0;
        // Unsigned long multiplication, truncated to N limbs.
        for i in 0..A.min(N) {
            let ai = a.0[i];
            let mut carry = 0u64;
            for j in 0..B {
                let k = i + j;
                if k + 1 >= N {
                    if k + 1 == N {
                        acc[k] = acc[k]
                            .wrapping_add(ai.wrapping_mul(b.0[j]))
                            .wrapping_add(carry);
                    }
                    carry = 0;
                    break;
                }
                let t = ai as u128 * b.0[j] as u128 + acc[k] as u128 + carry as u128;
                acc[k] = t as u64;
                carry = (t >> 64) as u64;
            }
            let mut k = i + B;
            while k < N {
                let (sum, c) = acc[k].overflowing_add(carry);
                acc[k] = sum;
                carry = c as u64;
                k += 1;
            }
        }
        // Sign corrections: subtract (b_u masked) << 64A and (a_u masked) << 64B.
        let mask_a = ((a.0[A - 1] as i64) >> 63) as u64;
        let mask_b = ((b.0[B - 1] as i64) >> 63) as u64;
        sub_shifted(acc, &b.0, A, mask_a);
        sub_shifted(acc, &a.0, B, mask_b);
    }

    /// Number of significant bits of `|self|` (0 for zero).
    #[must_use]
    pub fn magnitude_bits(&self) -> u32 {
        let (m, _) = self.unsigned_abs();
        for i in (0..N).rev() {
            if m[i] != 0 {
                return 64 * i as u32 + (64 - m[i].leading_zeros());
            }
        }
        0
    }

    /// The nearest `f64` (round to nearest, ties to even): relative error
    /// at most `2^-53`. Every value of up to 1024 bits is finite.
    #[must_use]
    #[inline]
    pub fn to_f64(&self) -> f64 {
        let (m, neg) = self.unsigned_abs();
        let mut top = N;
        while top > 0 && m[top - 1] == 0 {
            top -= 1;
        }
        let magnitude = if top <= 1 {
            if top == 0 { 0.0 } else { m[0] as f64 }
        } else {
            // Gather the 64 bits from the leading one down (bit 63 set), keep
            // the top 63 of them with a sticky bit for everything lower, and
            // convert as a signed 64-bit integer: the hardware rounds
            // correctly since the sticky bit lies 9 bits below the rounding
            // position. Then scale by an exact power of two.
            let hi = m[top - 1];
            let lz = hi.leading_zeros();
            let mid = m[top - 2];
            let bits = if lz == 0 {
                hi
            } else {
                hi << lz | mid >> (64 - lz)
            };
            let below = (mid << lz) | m[..top - 2].iter().fold(0, |acc, &l| acc | l);
            let sticky = ((bits & 1) | below != 0) as u64;
            let shift = 64 * (top as i32 - 1) - lz as i32 + 1;
            ((bits >> 1) | sticky) as i64 as f64 * pow2(shift)
        };
        if neg { -magnitude } else { magnitude }
    }
}

/// `acc −= (limbs & mask) << (64·shift)` modulo `2^(64·N)`.
#[inline]
fn sub_shifted<const N: usize, const L: usize>(
    acc: &mut [u64; N],
    limbs: &[u64; L],
    shift: usize,
    mask: u64,
) {
    let mut borrow = false;
    let mut k = shift;
    while k < N {
        let v = if k - shift < L {
            limbs[k - shift] & mask
        } else {
            0
        };
        let (d1, b1) = acc[k].overflowing_sub(v);
        let (d2, b2) = d1.overflowing_sub(borrow as u64);
        acc[k] = d2;
        borrow = b1 | b2;
        k += 1;
    }
}

/// `2^e` for `0 ≤ e ≤ 1023`, exactly.
#[inline]
fn pow2(e: i32) -> f64 {
    f64::from_bits(((1023 + e) as u64) << 52)
}

impl<const N: usize> PartialOrd for Int<N> {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl<const N: usize> Ord for Int<N> {
    fn cmp(&self, other: &Self) -> Ordering {
        match (self.is_negative(), other.is_negative()) {
            (true, false) => Ordering::Less,
            (false, true) => Ordering::Greater,
            // Same sign: two's-complement limbs compare as unsigned.
            _ => self.0.iter().rev().cmp(other.0.iter().rev()),
        }
    }
}

impl<const N: usize> Default for Int<N> {
    fn default() -> Self {
        Self::ZERO
    }
}

impl<const N: usize> fmt::Display for Int<N> {
    /// Decimal, with a leading `-` for negative values.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const CHUNK: u64 = 10_000_000_000_000_000_000; // 10^19
        let (mut m, neg) = self.unsigned_abs();
        let mut chunks = Vec::new();
        loop {
            // m /= 10^19, collecting the remainder.
            let mut rem = 0u128;
            for limb in m.iter_mut().rev() {
                let cur = rem << 64 | *limb as u128;
                *limb = (cur / CHUNK as u128) as u64;
                rem = cur % CHUNK as u128;
            }
            chunks.push(rem as u64);
            if m.iter().all(|&l| l == 0) {
                break;
            }
        }
        let mut digits = String::new();
        let mut iter = chunks.iter().rev();
        if let Some(first) = iter.next() {
            digits.push_str(&first.to_string());
        }
        for c in iter {
            digits.push_str(&format!("{c:019}"));
        }
        f.pad_integral(!neg, "", &digits)
    }
}

impl<const N: usize> fmt::Debug for Int<N> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Int<{}>({})", N, self)
    }
}
