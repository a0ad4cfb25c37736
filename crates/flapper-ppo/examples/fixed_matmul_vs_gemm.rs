//! What the fixed arithmetic costs: the training's matrix products (the paper's 540-256-128-64 layers
//! on one chunk of a 1536-sample minibatch: 384 rows, what each of the 4 chunks holds, and 96, a
//! quarter of one, what a thread computes when 16 threads share the chunks) through
//! `fixed_matmul::product` and through the `gemm` crate (CPU-dispatched, the same work), one thread,
//! best of 5 x 200 calls each.
//!
//!     cargo run --release -p flapper-ppo --example fixed_matmul_vs_gemm
//!     FLAPPER_SIMD=avx2 cargo run --release -p flapper-ppo --example fixed_matmul_vs_gemm

use std::time::Instant;

use flapper_ppo::fixed_matmul::{Simd, Start, Strided, product};

/// Best seconds per call of `f` over 5 rounds of 200 calls.
fn best_seconds(mut f: impl FnMut()) -> f64 {
    (0..5)
        .map(|_| {
            let start = Instant::now();
            (0..200).for_each(|_| f());
            start.elapsed().as_secs_f64() / 200.0
        })
        .fold(f64::MAX, f64::min)
}

fn main() {
    println!("fixed_matmul on the {} path against gemm, one thread:", Simd::active().name());
    for rows in [384, 96] {
        compare(rows);
    }
}

/// The products of one forward and backward pass over `rows` samples.
fn compare(rows: usize) {
    // (what, m, n, k, left operand transposed)
    let products = [
        (format!("layer 1 forward      {rows} x 540 -> 256"), rows, 256, 540, false),
        (format!("layer 1 weight grad  256 x 540 over {rows}"), 256, 540, rows, true),
        (format!("layer 2 forward      {rows} x 256 -> 128"), rows, 128, 256, false),
        (format!("layer 2 input grad   {rows} x 128 -> 256"), rows, 256, 128, false),
        (format!("layer 2 weight grad  128 x 256 over {rows}"), 128, 256, rows, true),
    ];
    let (mut fixed_total, mut gemm_total) = (0.0, 0.0);
    for (what, m, n, k, transposed) in products {
        let a: Vec<f32> = (0..m * k).map(|i| (i % 17) as f32 * 0.01).collect();
        let b: Vec<f32> = (0..k * n).map(|i| (i % 13) as f32 * 0.01).collect();
        let mut c = vec![0.0f32; m * n];
        let left = if transposed { Strided::transposed(&a, m) } else { Strided::rows(&a, k) };
        let fixed = best_seconds(|| product(&mut c, left, &b, m, n, k, Start::Zero));
        let (a_rs, a_cs) = if transposed { (1, m as isize) } else { (k as isize, 1) };
        let gemm = best_seconds(|| {
            // SAFETY: every index of the [m x k] (strided), [k x n] and [m x n] arrays lies inside them.
            unsafe {
                gemm::gemm(
                    m,
                    n,
                    k,
                    c.as_mut_ptr(),
                    1,
                    n as isize,
                    false,
                    a.as_ptr(),
                    a_cs,
                    a_rs,
                    b.as_ptr(),
                    1,
                    n as isize,
                    0.0,
                    1.0,
                    false,
                    false,
                    false,
                    gemm::Parallelism::None,
                )
            }
        });
        let gflops = |seconds: f64| 2.0 * (m * n * k) as f64 / seconds / 1e9;
        println!(
            "  {what}: fixed {:6.1} us ({:5.1} GFLOP/s), gemm {:6.1} us ({:5.1} GFLOP/s), ratio {:.2}",
            fixed * 1e6,
            gflops(fixed),
            gemm * 1e6,
            gflops(gemm),
            fixed / gemm
        );
        fixed_total += fixed;
        gemm_total += gemm;
    }
    println!(
        "  all five ({rows} rows): fixed {:6.1} us, gemm {:6.1} us, ratio {:.2}",
        fixed_total * 1e6,
        gemm_total * 1e6,
        fixed_total / gemm_total
    );
}
