//! A vectorizable `exp` for the ELU activation. `f32::exp` is a scalar libm call and, at the network's
//! sizes, costs as much as the matrix products; this one is branch-free arithmetic the compiler turns
//! into SIMD. Relative error below 5e-6 over [-80, 20] (measured by the test; it comes from rounding
//! x log2(e) to f32 at large |x|, where e^x is negligible next to ELU's -1 anyway).

#[cfg(target_arch = "x86_64")]
use crate::fixed_matmul::Simd;

/// e^x for x in [-87, 88] (clamped outside), by 2^(x log2 e) = 2^n * 2^f with a degree-6 polynomial for
/// 2^f on f in [-0.5, 0.5].
#[inline(always)]
pub fn exp_approx(x: f32) -> f32 {
    let x = x.clamp(-87.0, 88.0);
    let t = x * std::f32::consts::LOG2_E;
    let n = round_half_away(t);
    let f = t - n;
    // Taylor coefficients of 2^f = e^(f ln 2).
    const C1: f32 = std::f32::consts::LN_2;
    const C2: f32 = 0.240_226_5;
    const C3: f32 = 0.055_504_11;
    const C4: f32 = 0.009_618_129;
    const C5: f32 = 0.001_333_355_8;
    const C6: f32 = 0.000_154_035_3;
    let p = 1.0 + f * (C1 + f * (C2 + f * (C3 + f * (C4 + f * (C5 + f * C6)))));
    // Scale by 2^n through the exponent bits. n + 127 lies in [1, 254] (x is clamped), and adding 2^23
    // puts that integer, exactly, in the low mantissa bits: float arithmetic and bit moves that
    // vectorize, where `n as i32` (Rust's saturating cast) compiles to a scalar compare-and-select per
    // value. The same bits as (n as i32 + 127) << 23 for every n in range.
    const TWO_TO_23: f32 = 8_388_608.0;
    let biased = ((n + 127.0) + TWO_TO_23).to_bits() & 0x7f_ffff;
    p * f32::from_bits(biased << 23)
}

/// `t.round()` (halves away from zero) for |t| < 2^22, as plain arithmetic and selects that vectorize on
/// every x86-64 (`f32::round` is a library call without SSE4.1): the nearest integer with ties to even by
/// adding and removing 1.5 x 2^23 (where the spacing of f32 is 1), then ties moved away from zero and the
/// sign kept (-0.4 rounds to -0).
#[inline(always)]
fn round_half_away(t: f32) -> f32 {
    const SHIFT: f32 = 12_582_912.0;
    let even = (t + SHIFT) - SHIFT;
    if (t - even).abs() == 0.5 { t + 0.5f32.copysign(t) } else { even.copysign(t) }
}

/// ELU in place: x if x > 0, else e^x - 1.
pub fn elu_in_place(values: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    match Simd::active() {
        // SAFETY: `active` returns Avx512 only where the CPU has AVX-512F.
        Simd::Avx512 => return unsafe { x86::elu_avx512(values) },
        // SAFETY: `active` returns Avx2 only where the CPU has AVX2 and FMA.
        Simd::Avx2 => return unsafe { x86::elu_avx2(values) },
        Simd::Portable => {}
    }
    elu(values)
}

/// tanh in place, as 1 - 2 / (e^(2x) + 1) on the vectorizable exp.
pub fn tanh_in_place(values: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    match Simd::active() {
        // SAFETY: `active` returns Avx512 only where the CPU has AVX-512F.
        Simd::Avx512 => return unsafe { x86::tanh_avx512(values) },
        // SAFETY: `active` returns Avx2 only where the CPU has AVX2 and FMA.
        Simd::Avx2 => return unsafe { x86::tanh_avx2(values) },
        Simd::Portable => {}
    }
    tanh(values)
}

#[inline(always)]
fn elu(values: &mut [f32]) {
    for v in values {
        let negative = exp_approx(v.min(0.0)) - 1.0;
        *v = if *v > 0.0 { *v } else { negative };
    }
}

#[inline(always)]
fn tanh(values: &mut [f32]) {
    for v in values {
        *v = 1.0 - 2.0 / (exp_approx(2.0 * *v) + 1.0);
    }
}

/// The activations compiled for the wider vector paths of [`crate::fixed_matmul`] (x86-64 baseline code
/// has 4 lanes; these 8 and 16). Only the width changes: Rust never fuses a multiply and an add on its
/// own, and every operation here is IEEE 754's (no estimate instructions), so each path gives the same
/// bits (the test below compares them on every path the CPU has).
#[cfg(target_arch = "x86_64")]
mod x86 {
    /// # Safety
    /// The CPU has AVX-512F.
    #[target_feature(enable = "avx512f,avx2,fma")]
    pub(super) unsafe fn elu_avx512(values: &mut [f32]) {
        super::elu(values)
    }

    /// # Safety
    /// The CPU has AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn elu_avx2(values: &mut [f32]) {
        super::elu(values)
    }

    /// # Safety
    /// The CPU has AVX-512F.
    #[target_feature(enable = "avx512f,avx2,fma")]
    pub(super) unsafe fn tanh_avx512(values: &mut [f32]) {
        super::tanh(values)
    }

    /// # Safety
    /// The CPU has AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn tanh_avx2(values: &mut [f32]) {
        super::tanh(values)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exp_approx_matches_libm() {
        let mut worst: f32 = 0.0;
        for i in -80_000..=20_000 {
            let x = i as f32 * 1e-3;
            let (fast, exact) = (exp_approx(x), x.exp());
            worst = worst.max(((fast - exact) / exact).abs());
        }
        assert!(worst < 5e-6, "worst relative error {worst}");
        assert_eq!(exp_approx(0.0), 1.0);
        assert!(exp_approx(-200.0) >= 0.0 && exp_approx(-200.0) < 1e-37);
    }

    /// The exponent bits made by float arithmetic equal the integer cast's for every x, so trained
    /// networks and the shipped golden actions keep their bits: the polynomial written out again with
    /// `(n as i32 + 127) << 23`, compared on every step of 1/4096 over [-100, 100] and at the edges.
    #[test]
    fn the_vectorizable_scaling_equals_the_integer_cast_bit_for_bit() {
        fn with_cast(x: f32) -> f32 {
            let x = x.clamp(-87.0, 88.0);
            let t = x * std::f32::consts::LOG2_E;
            let n = round_half_away(t);
            let f = t - n;
            const C: [f32; 6] =
                [std::f32::consts::LN_2, 0.240_226_5, 0.055_504_11, 0.009_618_129, 0.001_333_355_8, 0.000_154_035_3];
            let p = 1.0 + f * (C[0] + f * (C[1] + f * (C[2] + f * (C[3] + f * (C[4] + f * C[5])))));
            p * f32::from_bits(((n as i32 + 127) as u32) << 23)
        }
        let mut values: Vec<f32> = (-409_600..=409_600).map(|i| i as f32 / 4096.0).collect();
        values.extend([-87.0, 88.0, -87.5, 88.5, f32::MIN, f32::MAX, f32::INFINITY, f32::NEG_INFINITY, -0.0]);
        for x in values {
            assert_eq!(exp_approx(x).to_bits(), with_cast(x).to_bits(), "e^{x}");
        }
        assert!(exp_approx(f32::NAN).is_nan());
    }

    /// Every vector path this CPU has computes the activations with the same bits as baseline code.
    #[test]
    #[cfg(target_arch = "x86_64")]
    fn the_activations_give_the_same_bits_on_every_vector_path() {
        let values: Vec<f32> = (-200_000..=200_000).map(|i| i as f32 * 5e-4 + 1e-5).collect();
        let (mut elu_expected, mut tanh_expected) = (values.clone(), values.clone());
        elu(&mut elu_expected);
        tanh(&mut tanh_expected);
        let same = |a: &[f32], b: &[f32]| a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits());
        let mut paths = 0;
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            let (mut e, mut t) = (values.clone(), values.clone());
            // SAFETY: the CPU has AVX2 and FMA.
            unsafe { (x86::elu_avx2(&mut e), x86::tanh_avx2(&mut t)) };
            assert!(same(&e, &elu_expected) && same(&t, &tanh_expected), "the AVX2 path differs");
            paths += 1;
        }
        if std::arch::is_x86_feature_detected!("avx512f") {
            let (mut e, mut t) = (values.clone(), values.clone());
            // SAFETY: the CPU has AVX-512F.
            unsafe { (x86::elu_avx512(&mut e), x86::tanh_avx512(&mut t)) };
            assert!(same(&e, &elu_expected) && same(&t, &tanh_expected), "the AVX-512 path differs");
            paths += 1;
        }
        let (mut e, mut t) = (values.clone(), values);
        elu_in_place(&mut e);
        tanh_in_place(&mut t);
        assert!(same(&e, &elu_expected) && same(&t, &tanh_expected), "the active path differs");
        eprintln!("{paths} vector paths compared");
    }

    #[test]
    fn rounding_equals_the_standard_library_bit_for_bit() {
        let mut values: Vec<f32> = (-300_000..=300_000).map(|i| i as f32 * 4.4e-4).collect();
        values.extend((-260..=260).map(|i| i as f32 * 0.5)); // every tie in exp_approx's range
        values.extend([-0.0, 0.0, 0.49999997, -0.49999997, 1.5, -2.5]);
        for t in values {
            assert_eq!(round_half_away(t).to_bits(), t.round().to_bits(), "{t}");
        }
    }

    #[test]
    fn tanh_matches_libm() {
        let mut v: Vec<f32> = (-2000..=2000).map(|i| i as f32 * 5e-3).collect();
        let exact: Vec<f32> = v.iter().map(|x| x.tanh()).collect();
        tanh_in_place(&mut v);
        for (a, b) in v.iter().zip(&exact) {
            assert!((a - b).abs() < 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn elu_is_identity_above_zero_and_saturates_at_minus_one() {
        let mut v = [2.0, 0.5, 0.0, -0.5, -30.0];
        elu_in_place(&mut v);
        assert_eq!(&v[..3], &[2.0, 0.5, 0.0]);
        assert!((v[3] - ((-0.5f32).exp() - 1.0)).abs() < 1e-6);
        assert!((v[4] + 1.0).abs() < 1e-6);
    }
}
