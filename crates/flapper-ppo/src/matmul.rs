//! Row-major matrix products on the `gemm` crate (runtime-dispatched SIMD kernels, x86-v4 included).

use gemm::Parallelism;

/// Which operand is stored transposed, and whether the product replaces or adds to the output.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Product {
    /// `a` is stored as its transpose, a [k x m] row-major array.
    pub a_transposed: bool,
    /// `b` is stored as its transpose, a [n x k] row-major array.
    pub b_transposed: bool,
    /// `c += a b` instead of `c = a b`.
    pub accumulate: bool,
}

impl Product {
    pub const PLAIN: Self = Self { a_transposed: false, b_transposed: false, accumulate: false };
}

/// `c[m x n] (=|+=) a[m x k] * b[k x n]`, all row-major (up to the transposes in `how`), using
/// `threads` threads (1 = this thread only).
#[allow(clippy::too_many_arguments)] // the shape of a BLAS call: output, operands, m n k, layout, threads
pub fn matmul(c: &mut [f32], a: &[f32], b: &[f32], m: usize, n: usize, k: usize, how: Product, threads: usize) {
    assert_eq!(c.len(), m * n, "output is not {m} x {n}");
    assert_eq!(a.len(), m * k, "left operand is not {m} x {k}");
    assert_eq!(b.len(), k * n, "right operand is not {k} x {n}");
    if m == 0 || n == 0 {
        return;
    }
    if k == 0 {
        if !how.accumulate {
            c.fill(0.0);
        }
        return;
    }
    // (row stride, column stride) of each operand as the product reads it.
    let (a_rs, a_cs) = if how.a_transposed { (1, m as isize) } else { (k as isize, 1) };
    let (b_rs, b_cs) = if how.b_transposed { (1, k as isize) } else { (n as isize, 1) };
    let parallelism = if threads > 1 { Parallelism::Rayon(threads) } else { Parallelism::None };
    // SAFETY: the lengths are checked above against the strides: every index the kernel forms lies
    // inside its slice, and `c` does not alias `a` or `b` (it is borrowed mutably).
    unsafe {
        gemm::gemm(
            m,
            n,
            k,
            c.as_mut_ptr(),
            1,
            n as isize,
            how.accumulate,
            a.as_ptr(),
            a_cs,
            a_rs,
            b.as_ptr(),
            b_cs,
            b_rs,
            if how.accumulate { 1.0 } else { 0.0 },
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn naive(a: &[f32], b: &[f32], m: usize, n: usize, k: usize, at: bool, bt: bool) -> Vec<f32> {
        let mut c = vec![0.0; m * n];
        for i in 0..m {
            for j in 0..n {
                for p in 0..k {
                    let x = if at { a[p * m + i] } else { a[i * k + p] };
                    let y = if bt { b[j * k + p] } else { b[p * n + j] };
                    c[i * n + j] += x * y;
                }
            }
        }
        c
    }

    #[test]
    fn matches_the_textbook_product_for_every_transpose() {
        let (m, n, k) = (7, 5, 9);
        let a: Vec<f32> = (0..m * k).map(|i| ((i * 37 % 11) as f32 - 5.0) * 0.1).collect();
        let b: Vec<f32> = (0..k * n).map(|i| ((i * 17 % 13) as f32 - 6.0) * 0.1).collect();
        for (at, bt) in [(false, false), (true, false), (false, true), (true, true)] {
            for threads in [1, 2] {
                let mut c = vec![1.0; m * n];
                matmul(
                    &mut c,
                    &a,
                    &b,
                    m,
                    n,
                    k,
                    Product { a_transposed: at, b_transposed: bt, accumulate: false },
                    threads,
                );
                let expected = naive(&a, &b, m, n, k, at, bt);
                for (x, y) in c.iter().zip(&expected) {
                    assert!((x - y).abs() < 1e-5, "{at} {bt}: {x} vs {y}");
                }
                matmul(
                    &mut c,
                    &a,
                    &b,
                    m,
                    n,
                    k,
                    Product { a_transposed: at, b_transposed: bt, accumulate: true },
                    threads,
                );
                for (x, y) in c.iter().zip(&expected) {
                    assert!((x - 2.0 * y).abs() < 1e-5, "accumulate {at} {bt}");
                }
            }
        }
    }
}
