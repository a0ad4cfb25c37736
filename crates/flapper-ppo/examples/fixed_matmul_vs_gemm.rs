//! What the fixed arithmetic costs: the training's matrix products (the paper's 540-256-128-64 layers
//! on a 96-row chunk of a minibatch) through `fixed_matmul::product` and through the `gemm` crate
//! (CPU-dispatched, the same work), one thread, best of 5 x 200 calls each.
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
    // (what, m, n, k, left operand transposed)
    let products = [
        ("layer 1 forward      96 x 540 -> 256", 96, 256, 540, false),
        ("layer 1 weight grad  256 x 540 over 96", 256, 540, 96, true),
        ("layer 2 forward      96 x 256 -> 128", 96, 128, 256, false),
        ("layer 2 input grad   96 x 128 -> 256", 96, 256, 128, false),
        ("layer 2 weight grad  128 x 256 over 96", 128, 256, 96, true),
    ];
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
    }
}
