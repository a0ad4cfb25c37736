//! Dense layers whose result is a function of the weights and the input only: the same bits on every
//! CPU (any x86-64 or aarch64, whatever its vector width), for one row or a batch, on any thread count.
//!
//! Evaluation, analysis, the report, rendering and the Python binding fly the policy through this path
//! (`ActorCritic::act_deterministic`), so that their tables reproduce exactly on another machine; a
//! flight is chaotic enough to turn a last-bit difference in an action into a different episode.
//! Training keeps the fast, CPU-dispatched kernels of [`crate::matmul`].
//!
//! What makes it exact: every dot product is summed in one fixed order, written out below (eight
//! running partial sums over the inputs taken in order, then a fixed pairwise tree), with a separate
//! multiply and add (never fused into an FMA), and no runtime feature dispatch. The eight partial sums
//! are the eight lanes of a `wide::f32x8` (two SSE registers on a baseline x86-64 build, one AVX
//! register where the build enables AVX, NEON on aarch64): lane-wise multiply and add are the same IEEE
//! operations as scalar ones, so the vector width changes how fast, not what is computed. Four outputs
//! are summed side by side only to keep the adder busy, and rows are done one after another: a row's
//! arithmetic is the same alone or in a batch.
//!
//! Written with explicit vectors because the compiler's own vectorization of the same loop shuffled
//! lanes and spilled its sums to the stack: the 540 x 256 layer took 22 us per observation that way and
//! 11 us this way (bit-identical; `flapper bench` prints the policy latency).

use wide::f32x8;

/// Partial sums per dot product (the lanes of an `f32x8`). Changing it changes the golden actions (`flapper-eval`'s test).
const LANES: usize = 8;
/// Outputs that share one pass over an input row: independent sums keep the adder busy.
const OUTPUT_BLOCK: usize = 4;

/// `out[r][j] = bias[j] + sum_i input[r][i] * weight[j][i]` for `rows` rows, all row-major: `input`
/// is [rows x fan_in], `weight` [fan_out x fan_in] (PyTorch's `nn.Linear` layout), `out` [rows x fan_out].
pub fn dense_layer(out: &mut [f32], input: &[f32], weight: &[f32], bias: &[f32], rows: usize) {
    let fan_out = bias.len();
    assert!(fan_out > 0 && weight.len().is_multiple_of(fan_out), "weight is not {fan_out} x fan_in");
    let fan_in = weight.len() / fan_out;
    assert_eq!(input.len(), rows * fan_in, "input is not {rows} x {fan_in}");
    assert_eq!(out.len(), rows * fan_out, "output is not {rows} x {fan_out}");
    if fan_in == 0 {
        out.chunks_exact_mut(fan_out).for_each(|row| row.copy_from_slice(bias));
        return;
    }
    let blocks = fan_out / OUTPUT_BLOCK;
    for (x, y) in input.chunks_exact(fan_in).zip(out.chunks_exact_mut(fan_out)) {
        for block in 0..blocks {
            let first = block * OUTPUT_BLOCK;
            let ws: [&[f32]; OUTPUT_BLOCK] = std::array::from_fn(|j| &weight[(first + j) * fan_in..][..fan_in]);
            let sums = dot_block(x, ws);
            for (j, sum) in sums.into_iter().enumerate() {
                y[first + j] = bias[first + j] + sum;
            }
        }
        for j in blocks * OUTPUT_BLOCK..fan_out {
            let [sum] = dot_block(x, [&weight[j * fan_in..][..fan_in]]);
            y[j] = bias[j] + sum;
        }
    }
}

/// The dot product of `x` with each of `J` weight rows, each in the fixed order described at the top.
#[inline(always)]
fn dot_block<const J: usize>(x: &[f32], ws: [&[f32]; J]) -> [f32; J] {
    let whole = x.len() / LANES * LANES;
    let mut partial = [f32x8::ZERO; J];
    for (c, xc) in x[..whole].chunks_exact(LANES).enumerate() {
        let xc = f32x8::from(lanes(xc));
        for (p, w) in partial.iter_mut().zip(&ws) {
            *p += xc * f32x8::from(lanes(&w[c * LANES..(c + 1) * LANES]));
        }
    }
    let mut partial = partial.map(|p| p.to_array());
    for (p, w) in partial.iter_mut().zip(&ws) {
        for (l, i) in (whole..x.len()).enumerate() {
            p[l] += x[i] * w[i];
        }
    }
    partial.map(|p| ((p[0] + p[4]) + (p[2] + p[6])) + ((p[1] + p[5]) + (p[3] + p[7])))
}

/// A whole chunk of `LANES` values.
#[inline(always)]
fn lanes(chunk: &[f32]) -> [f32; LANES] {
    chunk.try_into().expect("a whole chunk")
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The same sum written the slow way: lane l holds the inputs i with i mod 8 = l, in order.
    fn reference_dot(x: &[f32], w: &[f32]) -> f32 {
        let mut p = [0.0f32; LANES];
        for (i, (a, b)) in x.iter().zip(w).enumerate() {
            p[i % LANES] += a * b;
        }
        ((p[0] + p[4]) + (p[2] + p[6])) + ((p[1] + p[5]) + (p[3] + p[7]))
    }

    /// `n` test values spread over many magnitudes, so that a summation order shows in the last bits (also
    /// what `fixed_matmul`'s tests multiply).
    pub(crate) fn values(n: usize, seed: u32) -> Vec<f32> {
        (0..n as u32)
            .map(|i| {
                let h = (i.wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)).rotate_left(13);
                let mantissa = (h % 20_001) as f32 / 10_000.0 - 1.0;
                mantissa * [1e-3, 1.0, 30.0][(h % 3) as usize]
            })
            .collect()
    }

    #[test]
    fn follows_the_documented_order_bit_for_bit_for_any_batch() {
        for fan_in in [1, 7, 8, 9, 540] {
            let (fan_out, rows) = (5, 7);
            let (x, w, b) = (values(rows * fan_in, 1), values(fan_out * fan_in, 2), values(fan_out, 3));
            let mut batch = vec![0.0; rows * fan_out];
            dense_layer(&mut batch, &x, &w, &b, rows);
            for r in 0..rows {
                let xr = &x[r * fan_in..][..fan_in];
                let mut single = vec![0.0; fan_out];
                dense_layer(&mut single, xr, &w, &b, 1);
                for j in 0..fan_out {
                    let expected = b[j] + reference_dot(xr, &w[j * fan_in..][..fan_in]);
                    assert_eq!(batch[r * fan_out + j].to_bits(), expected.to_bits(), "fan_in {fan_in} row {r} out {j}");
                    assert_eq!(single[j].to_bits(), expected.to_bits(), "one row alone, fan_in {fan_in}");
                }
            }
        }
    }

    #[test]
    fn agrees_with_the_exact_product_to_rounding() {
        let (fan_in, fan_out, rows) = (540, 16, 3);
        let (x, w, b) = (values(rows * fan_in, 4), values(fan_out * fan_in, 5), values(fan_out, 6));
        let mut out = vec![0.0; rows * fan_out];
        dense_layer(&mut out, &x, &w, &b, rows);
        for r in 0..rows {
            for j in 0..fan_out {
                let exact: f64 =
                    b[j] as f64 + (0..fan_in).map(|i| x[r * fan_in + i] as f64 * w[j * fan_in + i] as f64).sum::<f64>();
                let magnitude: f64 = (0..fan_in).map(|i| (x[r * fan_in + i] * w[j * fan_in + i]).abs() as f64).sum();
                assert!((out[r * fan_out + j] as f64 - exact).abs() <= 1e-6 * magnitude, "row {r} out {j}");
            }
        }
    }
}
