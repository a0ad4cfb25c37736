//! A multilayer perceptron with ELU (or tanh) hidden layers and a linear output, forward and backward by hand on
//! [`fixed_matmul`](crate::fixed_matmul) (the same bits on every CPU). Parameters live in one flat vector (for
//! Adam, gradient clipping and checkpoints); each layer's weight is stored [out x in] row-major like PyTorch's
//! `nn.Linear`, so exported tensors load in PyTorch unchanged.

use std::ops::Range;
use std::sync::OnceLock;

use rand::Rng;

use serde::{Deserialize, Serialize};

use crate::exact_inference::dense_layer;
use crate::fast_math::{elu_in_place, tanh_in_place};
use crate::fixed_matmul::{Start, Strided, product};

/// One named parameter tensor inside the flat vector.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Tensor {
    /// `"{layer}.weight"` or `"{layer}.bias"`, as PyTorch names an `nn.Sequential` of Linear layers
    /// (layer indices count the activations too: 0, 2, 4, ...).
    pub name: String,
    pub shape: Vec<usize>,
    pub range: Range<usize>,
}

/// The hidden layers' nonlinearity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Activation {
    Elu,
    Tanh,
}

impl Activation {
    fn apply(self, values: &mut [f32]) {
        match self {
            Self::Elu => elu_in_place(values),
            Self::Tanh => tanh_in_place(values),
        }
    }

    /// Multiplies each `delta` by the derivative at the point whose activation output is `h`.
    fn backpropagate(self, delta: &mut [f32], outputs: &[f32]) {
        match self {
            // The slope is 1 above zero and e^x = h + 1 below; as a select (not a branch) it vectorizes,
            // and d * 1 is d exactly.
            Self::Elu => delta.iter_mut().zip(outputs).for_each(|(d, &h)| *d *= if h > 0.0 { 1.0 } else { h + 1.0 }),
            Self::Tanh => delta.iter_mut().zip(outputs).for_each(|(d, &h)| *d *= 1.0 - h * h),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
pub struct Mlp {
    /// Input size, hidden sizes, output size.
    sizes: Vec<usize>,
    activation: Activation,
    params: Vec<f32>,
    tensors: Vec<Tensor>,
    /// Each layer's weight transposed ([in x out]), the layout the forward product reads; made on
    /// first use after the parameters last changed.
    transposed: TransposedWeights,
}

/// A cache of the transposed weights, emptied by every mutable access to the parameters. Two MLPs
/// are equal when their parameters are, whatever their caches hold.
#[derive(Debug, Clone, Default)]
struct TransposedWeights(OnceLock<Vec<Vec<f32>>>);

impl PartialEq for TransposedWeights {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// Scratch buffers for one batch: every layer's output (kept for the backward pass) and two deltas.
#[derive(Debug, Clone, Default)]
pub struct Workspace {
    batch: usize,
    outputs: Vec<Vec<f32>>,
    delta: Vec<f32>,
    delta_next: Vec<f32>,
}

impl Mlp {
    /// `sizes` = [input, hidden..., output]. Weights and biases are drawn as PyTorch's default
    /// Linear initialization, U(-1/sqrt(fan_in), 1/sqrt(fan_in)); the output layer is scaled by
    /// `output_gain` (small for a policy's mean).
    pub fn new(sizes: &[usize], activation: Activation, output_gain: f32, rng: &mut impl Rng) -> Self {
        assert!(sizes.len() >= 2 && sizes.iter().all(|&s| s > 0), "an MLP needs an input and an output size");
        let tensors = tensor_layout(sizes);
        let mut params = vec![0.0; tensors.last().map_or(0, |t| t.range.end)];
        let layers = sizes.len() - 1;
        for (layer, pair) in sizes.windows(2).enumerate() {
            let bound = 1.0 / (pair[0] as f32).sqrt();
            let gain = if layer + 1 == layers { output_gain } else { 1.0 };
            for t in &tensors[2 * layer..2 * layer + 2] {
                for p in &mut params[t.range.clone()] {
                    *p = gain * rng.random_range(-bound..=bound);
                }
            }
        }
        Self { sizes: sizes.to_vec(), activation, params, tensors, transposed: TransposedWeights::default() }
    }

    /// An MLP with the given parameters (as `params()` returns them); `None` if their count does not
    /// match the sizes.
    pub fn with_params(sizes: &[usize], activation: Activation, params: Vec<f32>) -> Option<Self> {
        if sizes.len() < 2 || sizes.contains(&0) {
            return None;
        }
        let tensors = tensor_layout(sizes);
        (tensors.last().map_or(0, |t| t.range.end) == params.len()).then(|| Self {
            sizes: sizes.to_vec(),
            activation,
            params,
            tensors,
            transposed: TransposedWeights::default(),
        })
    }

    pub fn sizes(&self) -> &[usize] {
        &self.sizes
    }

    pub fn activation(&self) -> Activation {
        self.activation
    }

    pub fn input_size(&self) -> usize {
        self.sizes[0]
    }

    pub fn output_size(&self) -> usize {
        *self.sizes.last().expect("at least two sizes")
    }

    pub fn params(&self) -> &[f32] {
        &self.params
    }

    pub fn params_mut(&mut self) -> &mut [f32] {
        self.transposed = TransposedWeights::default();
        &mut self.params
    }

    /// Layer `layer`'s weight as [in x out] row-major, from the cache.
    fn transposed_weight(&self, layer: usize) -> &[f32] {
        let all = self.transposed.0.get_or_init(|| {
            (0..self.sizes.len() - 1)
                .map(|layer| {
                    let (fan_in, fan_out) = (self.sizes[layer], self.sizes[layer + 1]);
                    let weight = &self.params[self.tensors[2 * layer].range.clone()];
                    // In 16 x 16 blocks, so that reads and writes both stay within a few cache lines.
                    const BLOCK: usize = 16;
                    let mut t = vec![0.0; weight.len()];
                    for j0 in (0..fan_out).step_by(BLOCK) {
                        for i0 in (0..fan_in).step_by(BLOCK) {
                            for j in j0..(j0 + BLOCK).min(fan_out) {
                                for i in i0..(i0 + BLOCK).min(fan_in) {
                                    t[i * fan_out + j] = weight[j * fan_in + i];
                                }
                            }
                        }
                    }
                    t
                })
                .collect()
        });
        &all[layer]
    }

    /// This MLP with `extra` more inputs after its own, each weighted 0: it computes the same outputs
    /// whatever the new inputs hold (how a trained policy is given an input it never had).
    pub fn with_inputs_appended(&self, extra: usize) -> Self {
        let mut sizes = self.sizes.clone();
        sizes[0] += extra;
        let params = self.values_with_inputs_appended(&self.params, extra);
        Self::with_params(&sizes, self.activation, params).expect("widened to the widened sizes")
    }

    /// `values` in the layout of this MLP's parameters (e.g. Adam's moments), rearranged for
    /// [`Mlp::with_inputs_appended`]: each row of the first weight gains `extra` zeros.
    pub fn values_with_inputs_appended(&self, values: &[f32], extra: usize) -> Vec<f32> {
        assert_eq!(values.len(), self.params.len(), "not laid out as this MLP's parameters");
        let first = self.tensors[0].range.clone();
        let mut widened = Vec::with_capacity(values.len() + extra * self.sizes[1]);
        for row in values[first.clone()].chunks_exact(self.sizes[0]) {
            widened.extend_from_slice(row);
            widened.extend(std::iter::repeat_n(0.0, extra));
        }
        widened.extend_from_slice(&values[first.end..]);
        widened
    }

    pub fn tensors(&self) -> &[Tensor] {
        &self.tensors
    }

    /// Forward pass of `batch` rows of `input`; returns the output rows ([batch x output]). Each row's
    /// arithmetic is the same alone or in a batch, on any thread count (`threads` split the rows).
    pub fn forward<'w>(&self, input: &[f32], batch: usize, ws: &'w mut Workspace, threads: usize) -> &'w [f32] {
        assert_eq!(input.len(), batch * self.input_size(), "input is not {batch} x {}", self.input_size());
        let layers = self.sizes.len() - 1;
        ws.batch = batch;
        ws.outputs.resize_with(layers, Vec::new);
        for layer in 0..layers {
            let (fan_in, fan_out) = (self.sizes[layer], self.sizes[layer + 1]);
            let bias = &self.params[self.tensors[2 * layer + 1].range.clone()];
            let (before, rest) = ws.outputs.split_at_mut(layer);
            let previous: &[f32] = if layer == 0 { input } else { &before[layer - 1] };
            let out = &mut rest[0];
            out.resize(batch * fan_out, 0.0);
            // out = bias + x W^T, each element one chain from its bias.
            let weight_t = self.transposed_weight(layer);
            rows_in_parallel(
                out,
                Strided::rows(previous, fan_in),
                weight_t,
                batch,
                fan_out,
                fan_in,
                Start::Bias(bias),
                threads,
            );
            if layer + 1 < layers {
                self.activation.apply(out);
            }
        }
        &ws.outputs[layers - 1]
    }

    /// Forward pass of `batch` rows through [`exact_inference`](crate::exact_inference): the same bits
    /// on every CPU, for any batch (each row as if alone), one thread. Slower than [`Mlp::forward`] on
    /// large batches; what flying a trained policy uses.
    pub fn forward_exact<'w>(&self, input: &[f32], batch: usize, ws: &'w mut Workspace) -> &'w [f32] {
        assert_eq!(input.len(), batch * self.input_size(), "input is not {batch} x {}", self.input_size());
        let layers = self.sizes.len() - 1;
        ws.batch = batch;
        ws.outputs.resize_with(layers, Vec::new);
        for layer in 0..layers {
            let (weight, bias) = (&self.tensors[2 * layer].range, &self.tensors[2 * layer + 1].range);
            let (before, rest) = ws.outputs.split_at_mut(layer);
            let previous: &[f32] = if layer == 0 { input } else { &before[layer - 1] };
            let out = &mut rest[0];
            out.resize(batch * self.sizes[layer + 1], 0.0);
            dense_layer(out, previous, &self.params[weight.clone()], &self.params[bias.clone()], batch);
            if layer + 1 < layers {
                self.activation.apply(out);
            }
        }
        &ws.outputs[layers - 1]
    }

    /// Backward pass for the batch of the last `forward` on `ws` (whose `input` is passed again), given
    /// the loss gradient with respect to the outputs. Writes the gradient of every parameter into `grads`
    /// (same layout as `params`).
    pub fn backward(&self, ws: &mut Workspace, input: &[f32], d_output: &[f32], grads: &mut [f32], threads: usize) {
        let batch = ws.batch;
        assert_eq!(input.len(), batch * self.input_size(), "not the input of the last forward pass");
        let layers = self.sizes.len() - 1;
        assert_eq!(d_output.len(), batch * self.output_size());
        assert_eq!(grads.len(), self.params.len());
        ws.delta.clear();
        ws.delta.extend_from_slice(d_output);
        for layer in (0..layers).rev() {
            let (fan_in, fan_out) = (self.sizes[layer], self.sizes[layer + 1]);
            let (weight, bias) = (self.tensors[2 * layer].range.clone(), self.tensors[2 * layer + 1].range.clone());
            let previous: &[f32] = if layer == 0 { input } else { &ws.outputs[layer - 1] };
            // dW [out x in] = delta^T [out x batch] * previous [batch x in]
            let delta_t = Strided::transposed(&ws.delta, fan_out);
            rows_in_parallel(
                &mut grads[weight.clone()],
                delta_t,
                previous,
                fan_out,
                fan_in,
                batch,
                Start::Zero,
                threads,
            );
            let d_bias = &mut grads[bias];
            d_bias.fill(0.0);
            for row in ws.delta.chunks_exact(fan_out) {
                for (g, d) in d_bias.iter_mut().zip(row) {
                    *g += d;
                }
            }
            if layer > 0 {
                // delta_prev [batch x in] = delta [batch x out] * W [out x in], times the activation's slope.
                ws.delta_next.resize(batch * fan_in, 0.0);
                let w = &self.params[weight];
                let delta = Strided::rows(&ws.delta, fan_out);
                rows_in_parallel(&mut ws.delta_next, delta, w, batch, fan_in, fan_out, Start::Zero, threads);
                self.activation.backpropagate(&mut ws.delta_next, previous);
                std::mem::swap(&mut ws.delta, &mut ws.delta_next);
            }
        }
    }
}

/// [`product`] of `a` [m x k] and a row-major `b` [k x n] into `c` [m x n], the rows of `c` shared out
/// over `threads` threads in bands; each element's chain is the same in any band.
#[allow(clippy::too_many_arguments)] // the shape of a product: output, operands, m n k, start, threads
fn rows_in_parallel(c: &mut [f32], a: Strided, b: &[f32], m: usize, n: usize, k: usize, start: Start, threads: usize) {
    /// Fewer rows than this per band cost more to hand out than they save.
    const LEAST_ROWS_PER_BAND: usize = 16;
    let bands = threads.min(m / LEAST_ROWS_PER_BAND).max(1);
    if bands == 1 {
        product(c, a, b, m, n, k, start);
        return;
    }
    let rows_per_band = m.div_ceil(bands);
    rayon::scope(|scope| {
        for (band, c_band) in c.chunks_mut(rows_per_band * n).enumerate() {
            let first = band * rows_per_band;
            let a_band = Strided { values: &a.values[first * a.row_stride..], ..a };
            scope.spawn(move |_| product(c_band, a_band, b, c_band.len() / n, n, k, start));
        }
    });
}

/// Weight and bias of each layer, in order, inside one flat vector.
fn tensor_layout(sizes: &[usize]) -> Vec<Tensor> {
    let mut tensors = Vec::new();
    let mut offset = 0;
    for (layer, pair) in sizes.windows(2).enumerate() {
        let (fan_in, fan_out) = (pair[0], pair[1]);
        let index = 2 * layer;
        tensors.push(Tensor {
            name: format!("{index}.weight"),
            shape: vec![fan_out, fan_in],
            range: offset..offset + fan_in * fan_out,
        });
        offset += fan_in * fan_out;
        tensors.push(Tensor { name: format!("{index}.bias"), shape: vec![fan_out], range: offset..offset + fan_out });
        offset += fan_out;
    }
    tensors
}

#[cfg(test)]
mod tests {
    use super::*;

    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn appended_inputs_weigh_nothing_and_the_old_ones_keep_their_weights() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mlp = Mlp::new(&[4, 8, 3], Activation::Elu, 1.0, &mut rng);
        let wide = mlp.with_inputs_appended(2);
        assert_eq!(wide.sizes(), &[6, 8, 3]);
        let input: Vec<f32> = (0..2 * 4).map(|_| rng.random_range(-2.0..2.0)).collect();
        let mut wide_input = Vec::new();
        for row in input.chunks(4) {
            wide_input.extend_from_slice(row);
            wide_input.extend([rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)]);
        }
        let (mut narrow_ws, mut wide_ws) = (Workspace::default(), Workspace::default());
        let narrow_out = mlp.forward(&input, 2, &mut narrow_ws, 1);
        let wide_out = wide.forward(&wide_input, 2, &mut wide_ws, 1);
        assert_eq!(narrow_out, wide_out, "the new inputs changed the output");
        // Weight row j of the first layer: the old row, then zeros; every later tensor unchanged.
        let (old, new) = (&mlp.params()[..4 * 8], &wide.params()[..6 * 8]);
        for j in 0..8 {
            assert_eq!(&new[6 * j..6 * j + 4], &old[4 * j..4 * j + 4]);
            assert_eq!(&new[6 * j + 4..6 * j + 6], &[0.0, 0.0]);
        }
        assert_eq!(&wide.params()[6 * 8..], &mlp.params()[4 * 8..]);
    }

    /// Loss = sum(c * y) for fixed random c, in f64.
    fn loss(net: &Mlp, x: &[f32], batch: usize, c: &[f32]) -> f64 {
        let mut ws = Workspace::default();
        net.forward(x, batch, &mut ws, 1).iter().zip(c).map(|(y, c)| (*y as f64) * (*c as f64)).sum()
    }

    #[test]
    fn gradients_match_finite_differences_for_every_tensor() {
        for activation in [Activation::Elu, Activation::Tanh] {
            check_gradients(activation);
        }
    }

    fn check_gradients(activation: Activation) {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut net = Mlp::new(&[6, 8, 5, 3], activation, 1.0, &mut rng);
        let batch = 4;
        let x: Vec<f32> = (0..batch * 6).map(|_| rng.random_range(-1.5..1.5)).collect();
        let c: Vec<f32> = (0..batch * 3).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut ws = Workspace::default();
        net.forward(&x, batch, &mut ws, 1);
        let mut grads = vec![0.0; net.params().len()];
        net.backward(&mut ws, &x, &c, &mut grads, 1);
        let eps = 1e-2f32;
        for tensor in net.tensors().to_vec() {
            let mut worst: f64 = 0.0;
            for i in tensor.range.clone() {
                let original = net.params()[i];
                net.params_mut()[i] = original + eps;
                let up = loss(&net, &x, batch, &c);
                net.params_mut()[i] = original - eps;
                let down = loss(&net, &x, batch, &c);
                net.params_mut()[i] = original;
                let numeric = (up - down) / (2.0 * eps as f64);
                let error = (numeric - grads[i] as f64).abs() / (1e-2 + numeric.abs().max((grads[i] as f64).abs()));
                worst = worst.max(error);
            }
            assert!(worst < 2e-2, "{activation:?} {}: worst relative gradient error {worst:.2e}", tensor.name);
        }
    }

    #[test]
    fn layout_follows_pytorch_linear_layers() {
        let net = Mlp::new(&[540, 256, 128, 64, 5], Activation::Elu, 0.01, &mut ChaCha8Rng::seed_from_u64(0));
        let names: Vec<_> = net.tensors().iter().map(|t| (t.name.as_str(), t.shape.clone())).collect();
        assert_eq!(names[0], ("0.weight", vec![256, 540]));
        assert_eq!(names[1], ("0.bias", vec![256]));
        assert_eq!(names[6], ("6.weight", vec![5, 64]));
        assert_eq!(net.params().len(), 540 * 256 + 256 + 256 * 128 + 128 + 128 * 64 + 64 + 64 * 5 + 5);
        let output = &net.params()[net.tensors()[6].range.clone()];
        assert!(output.iter().all(|w| w.abs() <= 0.01 / 8.0 + 1e-9), "output gain applied");
    }

    #[test]
    fn forward_and_backward_give_the_same_bits_on_any_thread_count() {
        let mut rng = ChaCha8Rng::seed_from_u64(4);
        let net = Mlp::new(&[37, 48, 20, 3], Activation::Elu, 1.0, &mut rng);
        let batch = 70;
        let x: Vec<f32> = (0..batch * 37).map(|_| rng.random_range(-2.0..2.0)).collect();
        let d: Vec<f32> = (0..batch * 3).map(|_| rng.random_range(-1.0..1.0)).collect();
        let run = |threads: usize| {
            let mut ws = Workspace::default();
            let y = net.forward(&x, batch, &mut ws, threads).to_vec();
            let mut grads = vec![0.0; net.params().len()];
            net.backward(&mut ws, &x, &d, &mut grads, threads);
            (y.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), grads.iter().map(|g| g.to_bits()).collect::<Vec<_>>())
        };
        let one = run(1);
        for threads in [2, 3, 5] {
            assert!(run(threads) == one, "{threads} threads differ from one");
        }
    }

    #[test]
    fn batched_forward_equals_row_by_row_and_threads_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(9);
        let net = Mlp::new(&[10, 16, 4], Activation::Elu, 1.0, &mut rng);
        let x: Vec<f32> = (0..7 * 10).map(|_| rng.random_range(-1.0..1.0)).collect();
        let mut ws = Workspace::default();
        let all = net.forward(&x, 7, &mut ws, 2).to_vec();
        for (row, expected) in x.chunks(10).zip(all.chunks(4)) {
            let mut single = Workspace::default();
            let y = net.forward(row, 1, &mut single, 1);
            for (a, b) in y.iter().zip(expected) {
                assert!((a - b).abs() < 1e-5);
            }
        }
    }
}
