//! Bit budgets of the exact kernel (paper 1 §3.2, eqs. 7–9).
//!
//! Every integer quantity in `chisel_bsp` has a proven magnitude bound. The
//! bounds are derived here once, from the bound on input coordinates, and the
//! storage widths follow from them. Values enter the kernel only through
//! constructors that check these bounds and return [`crate::Error`] otherwise.
//!
//! Notation: `v⁺` bounds input coordinates, `n⁺` plane normal components,
//! `d⁺` plane offsets, `X⁺`/`W⁺` homogeneous vertex coordinates.
//!
//! | quantity                    | bound                         | bits (+sign) | stored as |
//! |-----------------------------|-------------------------------|--------------|-----------|
//! | input coordinate `v`        | `v⁺ = 2^26`                   | 27           | `i64`     |
//! | edge `e = v_j − v_i`        | `2^27`                        | 28           | `i64`     |
//! | normal `a, b, c`            | `n⁺ = 2·(2^27)² = 2^55`       | 56           | `i64`     |
//! | offset `d = −n·v`           | `3·n⁺·v⁺ < d⁺ = 2^83`         | 84           | `i128`    |
//! | `n_q × n_r` components      | `2·(n⁺)² = 2^111`             | 112          | `i128`    |
//! | `W = det(n_p, n_q, n_r)`    | `3^{3/2}·(n⁺)³ < 2^168`       | 169          | 192-bit   |
//! | `X, Y, Z`                   | `3^{3/2}·(n⁺)²·d⁺ < 2^196`    | 197          | 256-bit   |
//! | `classify = X·n_s + W·d_s`  | `16·(n⁺)³·d⁺ = 2^252`         | 253          | 256-bit   |
//!
//! The determinant bounds are Hadamard's inequality (`|det| ≤ ∏ ‖row‖₂`,
//! i.e. `3^{3/2}` for a 3×3 and `4² = 16` for a 4×4 matrix with entries in
//! `[−1, 1]`) after scaling each column by its entry bound. `classify` equals
//! (up to sign) the 4×4 determinant `|p q r s|` of the four planes, which is
//! why its bound is `16·(n⁺)³·d⁺` (eq. 7 with `b = 256`).
//!
//! Because every result fits its signed type, the kernel computes with
//! wrapping (modulo `2^bits`) arithmetic: intermediate overflow cancels and
//! the final value is exact.

/// Bits of an input coordinate's magnitude: `|v| ≤ 2^26` (±67 km at 1 mm).
pub const COORD_BITS: u32 = 26;
/// Largest admissible input coordinate magnitude, `v⁺ = 2^26`.
pub const MAX_COORD: i64 = 1 << COORD_BITS;

/// Bits of a plane normal component: `n⁺ = 2·(2·v⁺)² = 2^55`.
pub const NORMAL_BITS: u32 = 2 * (COORD_BITS + 1) + 1;
/// Largest admissible normal component magnitude, `n⁺ = 2^55`.
pub const MAX_NORMAL: i64 = 1 << NORMAL_BITS;

/// Bits of a plane offset: `|d| ≤ 3·n⁺·v⁺ < 2^(55+26+2) = 2^83`.
pub const OFFSET_BITS: u32 = NORMAL_BITS + COORD_BITS + 2;
/// Largest admissible plane offset magnitude, `d⁺ = 2^83`.
pub const MAX_OFFSET: i128 = 1 << OFFSET_BITS;

/// Bits of `W = det(n_p, n_q, n_r)`: `3^{3/2}·(n⁺)³ < 2^(3·55+3)`.
pub const W_BITS: u32 = 3 * NORMAL_BITS + 3;
/// Bits of `X, Y, Z`: `3^{3/2}·(n⁺)²·d⁺ < 2^(2·55+83+3)`.
pub const XYZ_BITS: u32 = 2 * NORMAL_BITS + OFFSET_BITS + 3;
/// Bits of a classification dot product: `16·(n⁺)³·d⁺ = 2^(3·55+83+4)`.
pub const CLASSIFY_BITS: u32 = 3 * NORMAL_BITS + OFFSET_BITS + 4;

// The storage widths must hold every bound with a sign bit to spare.
const _: () = assert!(NORMAL_BITS < 63);
const _: () = assert!(OFFSET_BITS < 127);
const _: () = assert!(2 * NORMAL_BITS + 1 < 127); // cross products in i128
const _: () = assert!(W_BITS < 192);
const _: () = assert!(XYZ_BITS < 256);
const _: () = assert!(CLASSIFY_BITS < 256);
// Sum of the three `d·(n×n)` terms of X (each < 2^(83+111)) stays below 2^196.
const _: () = assert!(OFFSET_BITS + 2 * NORMAL_BITS + 1 + 2 <= XYZ_BITS);
