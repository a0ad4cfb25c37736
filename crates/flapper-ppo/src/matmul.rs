//! Row-major matrix products for training: the `gemm` crate's runtime-dispatched SIMD kernels, used so
//! that the result is the same bits on every CPU with fused multiply-add (x86-64-v3 and up, aarch64),
//! whatever its vector width, cache sizes or thread count. Training then reproduces row for row on
//! another machine, not only on the CPU model that trained it.
//!
//! What the result is, element by element: the k terms are cut into `ceil(k / 512)` runs of equal
//! length (the last one shorter, see [`depth_runs`]); each run is summed from zero in order with one
//! fused multiply-add per term, and the runs are added to the output one after another. That is what
//! gemm's blocked kernels compute when the depth of one call is at most 512: each output element is one
//! register lane that takes the run's terms in order, and its smallest depth block is 512 (larger
//! blocks, chosen from the L1 cache's size on some CPUs, would change the grouping, so the runs are cut
//! here). Thread count splits outputs, never a sum.
//!
//! gemm's other paths are not used: for a single output row or column, or at most 256 outputs with both
//! operands contiguous along the depth, it sums across the lanes of a vector, whose count is the CPU's,
//! and a depth of 1 or 2 has a path of its own. Those shapes (the critic's one output, a one-row batch) go through [`ordered`],
//! a plain loop whose every element is summed in order with a separate multiply and add. The test below
//! checks both paths against their definitions, bit for bit, on the CPU it runs on.

use gemm::Parallelism;

/// The longest run of terms one kernel call sums: gemm's smallest depth block.
pub const MAX_DEPTH_RUN: usize = 512;

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
/// `threads` threads (1 = this thread only). The same bits on every CPU with FMA (module docs).
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
    if sums_across_lanes(m, n, k, how) {
        ordered(c, a, b, m, n, k, how);
        return;
    }
    for (run, range) in depth_runs(k).enumerate() {
        let accumulate = how.accumulate || run > 0;
        kernel(c, a, b, m, n, k, range, how, accumulate, threads);
    }
}

/// The runs the depth `0..k` is summed in: `ceil(k / 512)` runs, each `ceil(k / runs)` long but the last.
pub fn depth_runs(k: usize) -> impl Iterator<Item = std::ops::Range<usize>> {
    let runs = k.div_ceil(MAX_DEPTH_RUN).max(1);
    let length = k.div_ceil(runs);
    (0..k).step_by(length.max(1)).map(move |start| start..(start + length).min(k))
}

/// Whether gemm would take one of its paths that sum across vector lanes for this shape and layout
/// (its `gevv`, `gemv` and horizontal kernels; gemm-common 0.19, `gemm_basic_generic`).
fn sums_across_lanes(m: usize, n: usize, k: usize, how: Product) -> bool {
    let depth_contiguous = !how.a_transposed && how.b_transposed;
    m <= 1 || n <= 1 || k <= 2 || (depth_contiguous && m * n <= 16 * 16)
}

/// One gemm call over the depth terms `depth` (at most [`MAX_DEPTH_RUN`]): `c (=|+=) a[:, depth] b[depth, :]`.
#[allow(clippy::too_many_arguments)]
fn kernel(
    c: &mut [f32],
    a: &[f32],
    b: &[f32],
    m: usize,
    n: usize,
    k: usize,
    depth: std::ops::Range<usize>,
    how: Product,
    accumulate: bool,
    threads: usize,
) {
    debug_assert!(depth.len() <= MAX_DEPTH_RUN && depth.end <= k);
    // (row stride, column stride) of each operand as the product reads it, and where the run starts.
    let (a_rs, a_cs, a_start) =
        if how.a_transposed { (1, m as isize, depth.start * m) } else { (k as isize, 1, depth.start) };
    let (b_rs, b_cs, b_start) =
        if how.b_transposed { (1, k as isize, depth.start) } else { (n as isize, 1, depth.start * n) };
    let parallelism = if threads > 1 { Parallelism::Rayon(threads) } else { Parallelism::None };
    // SAFETY: the lengths of `a`, `b` and `c` are checked by `matmul` against m, n, k; the run lies inside
    // 0..k, so every index the kernel forms from these starts and strides lies inside its slice, and `c`
    // does not alias `a` or `b` (it is borrowed mutably).
    unsafe {
        gemm::gemm(
            m,
            n,
            depth.len(),
            c.as_mut_ptr(),
            1,
            n as isize,
            accumulate,
            a.as_ptr().add(a_start),
            a_cs,
            a_rs,
            b.as_ptr().add(b_start),
            b_cs,
            b_rs,
            if accumulate { 1.0 } else { 0.0 },
            1.0,
            false,
            false,
            false,
            parallelism,
        );
    }
}

/// The product with every element summed over `0..k` in order, a multiply and an add per term (never
/// fused): the same bits on every CPU. Vectors, where the compiler makes them, run across outputs, never
/// across a sum. For the small and thin shapes of [`sums_across_lanes`].
fn ordered(c: &mut [f32], a: &[f32], b: &[f32], m: usize, n: usize, k: usize, how: Product) {
    /// Outputs summed side by side when each is a dot product along `b`'s rows (independent sums keep
    /// the adder busy).
    const TILE: usize = 8;
    if !how.accumulate {
        c.fill(0.0);
    }
    let a_at = |i: usize, p: usize| if how.a_transposed { a[p * m + i] } else { a[i * k + p] };
    for (i, row) in c.chunks_exact_mut(n).enumerate() {
        if how.b_transposed {
            for (tile, outputs) in row.chunks_mut(TILE).enumerate() {
                let columns = &b[tile * TILE * k..][..outputs.len() * k];
                let mut sums = [0.0f32; TILE];
                sums[..outputs.len()].copy_from_slice(outputs);
                for p in 0..k {
                    let x = a_at(i, p);
                    for (sum, column) in sums.iter_mut().zip(columns.chunks_exact(k)) {
                        *sum += x * column[p];
                    }
                }
                outputs.copy_from_slice(&sums[..outputs.len()]);
            }
        } else {
            for p in 0..k {
                let x = a_at(i, p);
                for (out, y) in row.iter_mut().zip(&b[p * n..(p + 1) * n]) {
                    *out += x * y;
                }
            }
        }
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

    /// A deterministic operand of `len` values in [-1, 1) with many significant bits.
    fn operand(len: usize, seed: u64) -> Vec<f32> {
        let mut state = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (0..len)
            .map(|_| {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
                ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
            })
            .collect()
    }

    /// The module's definition of the result, element by element, written out.
    #[allow(clippy::too_many_arguments)]
    fn defined(c: &[f32], a: &[f32], b: &[f32], m: usize, n: usize, k: usize, how: Product) -> Vec<f32> {
        let at = |i: usize, p: usize| if how.a_transposed { a[p * m + i] } else { a[i * k + p] };
        let bt = |p: usize, j: usize| if how.b_transposed { b[j * k + p] } else { b[p * n + j] };
        let mut out = c.to_vec();
        for i in 0..m {
            for j in 0..n {
                let mut sum = if how.accumulate { Some(c[i * n + j]) } else { None };
                if sums_across_lanes(m, n, k, how) {
                    let mut s = sum.unwrap_or(0.0);
                    for p in 0..k {
                        s += at(i, p) * bt(p, j);
                    }
                    sum = Some(s);
                } else {
                    for run in depth_runs(k) {
                        let mut partial = 0.0f32;
                        for p in run {
                            partial = at(i, p).mul_add(bt(p, j), partial);
                        }
                        sum = Some(sum.map_or(partial, |s| s + partial));
                    }
                }
                out[i * n + j] = sum.unwrap_or(0.0);
            }
        }
        out
    }

    #[test]
    fn depth_runs_cover_the_depth_in_equal_runs_of_at_most_512() {
        for k in [1, 2, 511, 512, 513, 540, 1024, 1100, 1536, 6144] {
            let runs: Vec<_> = depth_runs(k).collect();
            assert_eq!(runs.len(), k.div_ceil(MAX_DEPTH_RUN), "{k}");
            assert_eq!(runs[0].start, 0);
            assert_eq!(runs.last().unwrap().end, k);
            assert!(runs.windows(2).all(|w| w[0].end == w[1].start && w[0].len() == runs[0].len()), "{k}: {runs:?}");
            assert!(runs.iter().all(|r| !r.is_empty() && r.len() <= MAX_DEPTH_RUN), "{k}: {runs:?}");
        }
        assert_eq!(depth_runs(540).map(|r| r.len()).collect::<Vec<_>>(), [270, 270]);
        assert_eq!(depth_runs(1100).map(|r| r.len()).collect::<Vec<_>>(), [367, 367, 366]);
    }

    /// The result is the definition's bits on this CPU, on both of gemm's paths and ours, in every layout,
    /// with 1 and 2 threads: shapes of the training's layers (a 540-wide observation, 256 rows of a
    /// rollout, the critic's one output), depths over 512, and small ones.
    #[test]
    fn every_element_is_the_defined_sum_bit_for_bit() {
        let shapes = [
            (70, 90, 1100), // three depth runs, outputs over gemm's 64 x 64 small-size branch
            (96, 64, 540),  // the first layer's depth: two runs of 270
            (33, 17, 64),
            (256, 1, 64), // the critic's output over a rollout's 256 environments
            (1, 128, 700),
            (7, 5, 2),
            (12, 20, 40), // 240 outputs: gemm's horizontal kernel when the depth is contiguous
        ];
        for (shape, &(m, n, k)) in shapes.iter().enumerate() {
            let a = operand(m * k, 3 * shape as u64);
            let b = operand(k * n, 3 * shape as u64 + 1);
            let start = operand(m * n, 3 * shape as u64 + 2);
            for (at, bt, accumulate) in (0..8).map(|x| (x & 1 == 1, x & 2 == 2, x & 4 == 4)) {
                let how = Product { a_transposed: at, b_transposed: bt, accumulate };
                let expected = defined(&start, &a, &b, m, n, k, how);
                for threads in [1, 2] {
                    let mut c = start.clone();
                    matmul(&mut c, &a, &b, m, n, k, how, threads);
                    let differing = c.iter().zip(&expected).filter(|(x, y)| x.to_bits() != y.to_bits()).count();
                    assert_eq!(
                        differing, 0,
                        "{m} x {n} x {k}, {how:?}, {threads} threads: {differing} elements differ"
                    );
                }
            }
        }
    }
}
