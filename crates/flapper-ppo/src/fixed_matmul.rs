//! The matrix products of training, in one fixed arithmetic: the same bits on every x86-64 CPU (and any
//! other), whatever its vector width, and on any thread count.
//!
//! The rule: every output element is one chain of fused multiply-adds in increasing `p`,
//! `c = fma(a[i][p], b[p][j], c)` for p = 0, 1, ..., k - 1, starting from zero, from a bias, or from
//! the value already in the output. Nothing else touches it: no partial sums, no blocking of `k`, no
//! sum across vector lanes. A vector holds neighbouring *outputs* (columns j), never neighbouring
//! terms of one sum, so 8 lanes (AVX2), 16 lanes (AVX-512) and one lane (the portable path) compute
//! each element identically; only the speed differs. A fused multiply-add rounds once, exactly as
//! IEEE 754 defines it, in hardware or in software.
//!
//! Where it sits: [`crate::mlp`] runs its forward and backward passes through [`product`]; the
//! learner splits each minibatch into a fixed number of chunks and sums their gradients in a fixed
//! order (`crate::ppo`), so threads change how fast, not what is computed. Flying a trained policy
//! keeps its own fixed order ([`crate::exact_inference`]), which the shipped golden actions pin.
//!
//! Which vector path runs is decided once per process from the CPU, and can be forced narrower with
//! the environment variable `FLAPPER_SIMD` (`avx512`, `avx2` or `portable`), which is how the tests
//! check that the paths agree bit for bit. `gemm`, which training used before, picks kernels and a
//! blocking of `k` from the CPU it finds: its results differed between CPU models.

use std::sync::OnceLock;

/// The left operand `a[i][p] = values[i * row_stride + p * column_stride]`: a row-major matrix, or
/// the transpose of one, read in place.
#[derive(Debug, Clone, Copy)]
pub struct Strided<'a> {
    pub values: &'a [f32],
    pub row_stride: usize,
    pub column_stride: usize,
}

impl<'a> Strided<'a> {
    /// A row-major [rows x columns] matrix.
    pub fn rows(values: &'a [f32], columns: usize) -> Self {
        Self { values, row_stride: columns, column_stride: 1 }
    }

    /// The transpose of a row-major [rows x columns] matrix: `a[i][p]` is `values[p][i]`.
    pub fn transposed(values: &'a [f32], columns: usize) -> Self {
        Self { values, row_stride: 1, column_stride: columns }
    }

    #[inline(always)]
    fn at(&self, i: usize, p: usize) -> f32 {
        self.values[i * self.row_stride + p * self.column_stride]
    }
}

/// Where each output element's chain starts.
#[derive(Debug, Clone, Copy)]
pub enum Start<'a> {
    /// From zero: `c = a b`.
    Zero,
    /// From `bias[j]` for every row: `c = bias + a b`.
    Bias(&'a [f32]),
    /// From the output's own value: `c += a b` (one chain continued, not a separate sum added).
    Output,
}

/// `c[i][j] = start + sum_p a[i][p] b[p][j]` for an [m x n] row-major `c` and a [k x n] row-major
/// `b`, each element one fused multiply-add chain in increasing `p` (the module's rule).
pub fn product(c: &mut [f32], a: Strided, b: &[f32], m: usize, n: usize, k: usize, start: Start) {
    assert_eq!(c.len(), m * n, "output is not {m} x {n}");
    assert_eq!(b.len(), k * n, "right operand is not {k} x {n}");
    if m > 0 && k > 0 {
        let last = (m - 1) * a.row_stride + (k - 1) * a.column_stride;
        assert!(last < a.values.len(), "left operand is smaller than {m} x {k}");
    }
    if let Start::Bias(bias) = start {
        assert_eq!(bias.len(), n, "bias is not {n} long");
    }
    if m == 0 || n == 0 {
        return;
    }
    let shape = Shape { m, n, k };
    match Simd::active() {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `active` returns Avx512 only where the CPU has AVX-512F; the shapes are checked above.
        Simd::Avx512 => unsafe { x86::product_avx512(c, a, b, shape, start) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `active` returns Avx2 only where the CPU has AVX2 and FMA; the shapes are checked above.
        Simd::Avx2 => unsafe { x86::product_avx2(c, a, b, shape, start) },
        _ => portable(c, a, b, shape, start),
    }
}

#[derive(Debug, Clone, Copy)]
struct Shape {
    m: usize,
    n: usize,
    k: usize,
}

/// Terms of `p` taken per sweep over the output by the vector paths. Each element's chain goes on
/// where the last sweep stored it: the same operations in the same order, whatever the sweep's length.
/// Where a sweep's columns of `b` are packed (`x86::PACK_FROM_ROW_TILES`), [`KC_PACKED`] keeps the
/// packed panel (128 x 64 floats, 32 KiB for AVX-512) inside a 48 KiB L1 cache.
#[cfg(target_arch = "x86_64")]
const KC: usize = 256;
#[cfg(target_arch = "x86_64")]
const KC_PACKED: usize = 128;

/// The vector path that computes [`product`]: a speed, never a result.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Simd {
    /// 16 lanes of f32 (x86-64 with AVX-512F).
    Avx512,
    /// 8 lanes of f32 (x86-64 with AVX2 and FMA).
    Avx2,
    /// One element at a time, `f32::mul_add` (any CPU).
    Portable,
}

/// The environment variable that forces a narrower path than the CPU offers.
pub const SIMD_VARIABLE: &str = "FLAPPER_SIMD";

impl Simd {
    /// The path this process uses: `FLAPPER_SIMD`'s where it is set and valid
    /// ([`Simd::from_environment`]), else the widest the CPU has. A program checks the variable with
    /// `from_environment` first, to refuse a wrong one instead of running on the widest path.
    pub fn active() -> Self {
        static ACTIVE: OnceLock<Simd> = OnceLock::new();
        *ACTIVE.get_or_init(|| Self::from_environment().ok().flatten().unwrap_or_else(Self::widest))
    }

    /// The path `FLAPPER_SIMD` asks for: `None` where it is unset or empty; an error naming the value
    /// where it is not a path's name or asks a wider path than this CPU has.
    pub fn from_environment() -> Result<Option<Self>, String> {
        let Ok(value) = std::env::var(SIMD_VARIABLE) else { return Ok(None) };
        if value.trim().is_empty() {
            return Ok(None);
        }
        let asked = Self::from_name(&value)
            .ok_or_else(|| format!("{SIMD_VARIABLE}='{value}' is not one of avx512, avx2, portable"))?;
        let widest = Self::widest();
        if asked.lanes() > widest.lanes() {
            return Err(format!(
                "{SIMD_VARIABLE}='{value}' asks for a wider vector path than this CPU has (its widest: {})",
                widest.name()
            ));
        }
        Ok(Some(asked))
    }

    /// The widest path this CPU runs.
    pub fn widest() -> Self {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx512f") {
                return Self::Avx512;
            }
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
                return Self::Avx2;
            }
        }
        Self::Portable
    }

    /// `avx512`, `avx2` or `portable`.
    pub fn from_name(name: &str) -> Option<Self> {
        match name.trim().to_ascii_lowercase().as_str() {
            "avx512" => Some(Self::Avx512),
            "avx2" => Some(Self::Avx2),
            "portable" => Some(Self::Portable),
            _ => None,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Self::Avx512 => "avx512",
            Self::Avx2 => "avx2",
            Self::Portable => "portable",
        }
    }

    /// f32 lanes per vector.
    pub fn lanes(self) -> usize {
        match self {
            Self::Avx512 => 16,
            Self::Avx2 => 8,
            Self::Portable => 1,
        }
    }
}

/// The rule written out one element at a time: the definition every vector path must equal.
fn portable(c: &mut [f32], a: Strided, b: &[f32], shape: Shape, start: Start) {
    let Shape { m, n, k } = shape;
    for i in 0..m {
        for j in 0..n {
            let mut sum = match start {
                Start::Zero => 0.0,
                Start::Bias(bias) => bias[j],
                Start::Output => c[i * n + j],
            };
            for p in 0..k {
                sum = a.at(i, p).mul_add(b[p * n + j], sum);
            }
            c[i * n + j] = sum;
        }
    }
}

#[cfg(target_arch = "x86_64")]
mod x86 {
    //! The vector paths. One generic kernel, [`blocks`], instantiated inside a function compiled for
    //! each instruction set: an output tile of R rows by V vectors of columns is held in registers
    //! while `p` runs from 0 to k - 1; columns that do not fill a vector are computed with masked
    //! loads and stores, lane for lane the same operations.

    use std::arch::x86_64::*;

    use super::{Shape, Start, Strided};

    /// One instruction set's f32 vector.
    trait Lanes: Copy {
        const WIDTH: usize;
        unsafe fn zero() -> Self;
        unsafe fn splat(x: f32) -> Self;
        /// The first `count` lanes from `ptr`, zeros after (count = WIDTH: a whole vector).
        unsafe fn load(ptr: *const f32, count: usize) -> Self;
        unsafe fn store(self, ptr: *mut f32, count: usize);
        /// `a * b + self`, rounded once.
        unsafe fn fma(self, a: Self, b: Self) -> Self;
        /// [`tile`] compiled for this instruction set as a function of its own (inlining every tile
        /// into one function made the compiler spill the accumulators).
        unsafe fn tile<const R: usize, const V: usize>(operands: Operands, place: Place);
    }

    /// What every tile reads and writes.
    #[derive(Clone, Copy)]
    struct Operands<'a> {
        c: *mut f32,
        a: Strided<'a>,
        shape: Shape,
        start: Start<'a>,
    }

    /// A tile: rows i..i+R, columns j.. (V vectors, `last` lanes of the last), terms `first..end`;
    /// `b[p][j..]` read at `panel + (p - first) * panel_stride` (`b` itself, or the sweep's copy of
    /// the tile's columns packed side by side, [`PACK_FROM_ROW_TILES`]).
    #[derive(Clone, Copy)]
    struct Place {
        i: usize,
        j: usize,
        last: usize,
        first: usize,
        end: usize,
        panel: *const f32,
        panel_stride: usize,
    }

    /// Row tiles from which a sweep's columns of `b` are first copied into one contiguous panel:
    /// rows of `b` lie `n` floats apart, and with n a multiple of 256 (1 KiB) the rows of one tile
    /// fall into a quarter of the L1 cache's sets and evict each other before the next row tile reads
    /// them again. Packed, the panel is read from L1 by every row tile. The values are the same, so
    /// the arithmetic is too; only where they are read from changes.
    const PACK_FROM_ROW_TILES: usize = 24;

    thread_local! {
        /// Each thread's panel buffer (KC x V x WIDTH floats at most, 64 KiB for AVX-512).
        static PANEL: std::cell::RefCell<Vec<f32>> = const { std::cell::RefCell::new(Vec::new()) };
    }

    /// # Safety
    /// The CPU has AVX2 and FMA; the place lies inside the operands' shapes.
    #[target_feature(enable = "avx2,fma")]
    #[inline(never)]
    unsafe fn tile_avx2<const R: usize, const V: usize>(operands: Operands, place: Place) {
        // SAFETY: as this function's contract.
        unsafe { tile::<Avx2, R, V>(operands, place) }
    }

    /// # Safety
    /// The CPU has AVX-512F; the place lies inside the operands' shapes.
    #[target_feature(enable = "avx512f,avx2,fma")]
    #[inline(never)]
    unsafe fn tile_avx512<const R: usize, const V: usize>(operands: Operands, place: Place) {
        // SAFETY: as this function's contract.
        unsafe { tile::<Avx512, R, V>(operands, place) }
    }

    #[derive(Clone, Copy)]
    struct Avx2(__m256);

    #[derive(Clone, Copy)]
    struct Avx512(__m512);

    /// Lane masks for AVX2's masked moves: the first `count` lanes set.
    #[inline(always)]
    unsafe fn avx2_mask(count: usize) -> __m256i {
        const LANES: [i32; 16] = [-1, -1, -1, -1, -1, -1, -1, -1, 0, 0, 0, 0, 0, 0, 0, 0];
        // SAFETY: 8 - count lies in 0..=8 for count in 0..=8, so the 8 values read lie inside LANES.
        unsafe { _mm256_loadu_si256(LANES.as_ptr().add(8 - count) as *const __m256i) }
    }

    impl Lanes for Avx2 {
        const WIDTH: usize = 8;
        #[inline(always)]
        unsafe fn zero() -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm256_setzero_ps() })
        }
        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm256_set1_ps(x) })
        }
        #[inline(always)]
        unsafe fn load(ptr: *const f32, count: usize) -> Self {
            // SAFETY: the caller hands `count` readable values at `ptr`.
            unsafe {
                if count == Self::WIDTH {
                    Self(_mm256_loadu_ps(ptr))
                } else {
                    Self(_mm256_maskload_ps(ptr, avx2_mask(count)))
                }
            }
        }
        #[inline(always)]
        unsafe fn store(self, ptr: *mut f32, count: usize) {
            // SAFETY: the caller hands `count` writable values at `ptr`.
            unsafe {
                if count == Self::WIDTH {
                    _mm256_storeu_ps(ptr, self.0)
                } else {
                    _mm256_maskstore_ps(ptr, avx2_mask(count), self.0)
                }
            }
        }
        #[inline(always)]
        unsafe fn fma(self, a: Self, b: Self) -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm256_fmadd_ps(a.0, b.0, self.0) })
        }
        #[inline(always)]
        unsafe fn tile<const R: usize, const V: usize>(operands: Operands, place: Place) {
            // SAFETY: only the AVX2 path (checked by `product`) reaches here, with places inside the shapes.
            unsafe { tile_avx2::<R, V>(operands, place) }
        }
    }

    impl Lanes for Avx512 {
        const WIDTH: usize = 16;
        #[inline(always)]
        unsafe fn zero() -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm512_setzero_ps() })
        }
        #[inline(always)]
        unsafe fn splat(x: f32) -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm512_set1_ps(x) })
        }
        #[inline(always)]
        unsafe fn load(ptr: *const f32, count: usize) -> Self {
            // SAFETY: the caller hands `count` readable values at `ptr`; masked-off lanes are not read.
            unsafe { Self(_mm512_maskz_loadu_ps(((1u32 << count) - 1) as __mmask16, ptr)) }
        }
        #[inline(always)]
        unsafe fn store(self, ptr: *mut f32, count: usize) {
            // SAFETY: the caller hands `count` writable values at `ptr`; masked-off lanes are not written.
            unsafe { _mm512_mask_storeu_ps(ptr, ((1u32 << count) - 1) as __mmask16, self.0) }
        }
        #[inline(always)]
        unsafe fn fma(self, a: Self, b: Self) -> Self {
            // SAFETY: called only inside the kernels compiled for this instruction set.
            Self(unsafe { _mm512_fmadd_ps(a.0, b.0, self.0) })
        }
        #[inline(always)]
        unsafe fn tile<const R: usize, const V: usize>(operands: Operands, place: Place) {
            // SAFETY: only the AVX-512 path (checked by `product`) reaches here, with places inside the shapes.
            unsafe { tile_avx512::<R, V>(operands, place) }
        }
    }

    /// # Safety
    /// The CPU has AVX2 and FMA; `c`, `a` and `b` hold the shapes `product` checked.
    #[target_feature(enable = "avx2,fma")]
    pub(super) unsafe fn product_avx2(c: &mut [f32], a: Strided, b: &[f32], shape: Shape, start: Start) {
        // 4 x 3 accumulators, 3 loads and a broadcast: 16 registers.
        // SAFETY: as this function's contract.
        unsafe { blocks::<Avx2, 6, 2>(c, a, b, shape, start) }
    }

    /// # Safety
    /// The CPU has AVX-512F; `c`, `a` and `b` hold the shapes `product` checked.
    #[target_feature(enable = "avx512f,avx2,fma")]
    pub(super) unsafe fn product_avx512(c: &mut [f32], a: Strided, b: &[f32], shape: Shape, start: Start) {
        // 6 x 4 accumulators of 16 lanes, 4 loads and a broadcast: 29 of the 32 registers.
        // SAFETY: as this function's contract.
        unsafe { blocks::<Avx512, 6, 4>(c, a, b, shape, start) }
    }

    /// Covers the output with tiles, in sweeps of [`KC`](super::KC) (or [`KC_PACKED`](super::KC_PACKED)) terms: R rows by V whole vectors
    /// while they fit, then one vector at a time for the columns left (the last one masked).
    #[inline(always)]
    unsafe fn blocks<L: Lanes, const R: usize, const V: usize>(
        c: &mut [f32],
        a: Strided,
        b: &[f32],
        shape: Shape,
        start: Start,
    ) {
        let Shape { m, n, k } = shape;
        let mut operands = Operands { c: c.as_mut_ptr(), a, shape, start };
        let pack = m / R >= PACK_FROM_ROW_TILES;
        let sweep = if pack { super::KC_PACKED } else { super::KC };
        PANEL.with_borrow_mut(|panel| {
            let mut first = 0;
            loop {
                let end = (first + sweep).min(k);
                let mut j = 0;
                while j < n {
                    let whole = j + V * L::WIDTH <= n;
                    let last = if whole { L::WIDTH } else { (n - j).min(L::WIDTH) };
                    let columns = if whole { V * L::WIDTH } else { last };
                    let (panel_ptr, panel_stride) = if pack {
                        panel.clear();
                        for p in first..end {
                            panel.extend_from_slice(&b[p * n + j..p * n + j + columns]);
                        }
                        (panel.as_ptr(), columns)
                    } else {
                        // SAFETY: row `first`, column j lies inside b ([k x n]).
                        (unsafe { b.as_ptr().add(first * n + j) }, n)
                    };
                    let place = |i| Place { i, j, last, first, end, panel: panel_ptr, panel_stride };
                    let mut i = 0;
                    // SAFETY (every call): the tiles lie inside the shapes `product` checked.
                    while i + R <= m {
                        unsafe {
                            if whole {
                                L::tile::<R, V>(operands, place(i))
                            } else {
                                L::tile::<R, 1>(operands, place(i))
                            }
                        };
                        i += R;
                    }
                    for i in i..m {
                        unsafe {
                            if whole {
                                L::tile::<1, V>(operands, place(i))
                            } else {
                                L::tile::<1, 1>(operands, place(i))
                            }
                        };
                    }
                    j += columns;
                }
                if end == k {
                    break;
                }
                // Later sweeps go on with each element's chain where the last one stored it.
                operands.start = Start::Output;
                first = end;
            }
        });
    }

    /// The tile at `place`: each element's chain over the place's terms, held in registers.
    #[inline(always)]
    unsafe fn tile<L: Lanes, const R: usize, const V: usize>(operands: Operands, place: Place) {
        let Operands { c: c_ptr, a, shape, start } = operands;
        let Place { i, j, last, first, end, panel, panel_stride } = place;
        let n = shape.n;
        let width = |v: usize| if v + 1 == V { last } else { L::WIDTH };
        // SAFETY: rows i..i+R and columns j..j+(V-1)*WIDTH+last lie inside c ([m x n]), the panel (terms
        // first..end of those columns) and the bias ([n]); a[i + r][p] lies inside a (checked by `product`).
        unsafe {
            let mut sums = [[L::zero(); V]; R];
            for (r, row) in sums.iter_mut().enumerate() {
                for (v, sum) in row.iter_mut().enumerate() {
                    let column = j + v * L::WIDTH;
                    *sum = match start {
                        Start::Zero => L::zero(),
                        Start::Bias(bias) => L::load(bias.as_ptr().add(column), width(v)),
                        Start::Output => L::load(c_ptr.add((i + r) * n + column), width(v)),
                    };
                }
            }
            for p in first..end {
                let row = panel.add((p - first) * panel_stride);
                let bs: [L; V] = std::array::from_fn(|v| L::load(row.add(v * L::WIDTH), width(v)));
                for (r, sums_r) in sums.iter_mut().enumerate() {
                    let x = L::splat(*a.values.get_unchecked((i + r) * a.row_stride + p * a.column_stride));
                    for (sum, bv) in sums_r.iter_mut().zip(&bs) {
                        *sum = sum.fma(x, *bv);
                    }
                }
            }
            for (r, row) in sums.iter().enumerate() {
                for (v, sum) in row.iter().enumerate() {
                    sum.store(c_ptr.add((i + r) * n + j + v * L::WIDTH), width(v));
                }
            }
        }
    }

    #[cfg(test)]
    pub(super) fn all_paths(c: &mut [f32], a: Strided, b: &[f32], shape: Shape, start: Start) -> Vec<Vec<f32>> {
        let mut results = Vec::new();
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
            let mut out = c.to_vec();
            // SAFETY: the CPU has AVX2 and FMA; the test's shapes are consistent.
            unsafe { product_avx2(&mut out, a, b, shape, start) };
            results.push(out);
        }
        if std::arch::is_x86_feature_detected!("avx512f") {
            let mut out = c.to_vec();
            // SAFETY: the CPU has AVX-512F; the test's shapes are consistent.
            unsafe { product_avx512(&mut out, a, b, shape, start) };
            results.push(out);
        }
        results
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exact_inference::tests::values;

    /// Every vector path this CPU has, and the portable one, give the same bits as the rule written
    /// out, for shapes with and without ragged edges, each start, and a transposed left operand.
    #[test]
    fn every_vector_path_follows_the_rule_bit_for_bit() {
        // (150, 70, 300): enough row tiles that each sweep's columns of b are packed, over 3 sweeps, ragged.
        let shapes =
            [(1, 1, 1), (7, 5, 9), (6, 32, 3), (13, 47, 29), (96, 256, 540), (5, 540, 17), (12, 1, 64), (150, 70, 300)];
        for (m, n, k) in shapes {
            for transposed in [false, true] {
                let a_values = values(m * k, 1);
                let a = if transposed { Strided::transposed(&a_values, m) } else { Strided::rows(&a_values, k) };
                let (b, bias, initial) = (values(k * n, 2), values(n, 3), values(m * n, 4));
                for start in [Start::Zero, Start::Bias(&bias), Start::Output] {
                    let shape = Shape { m, n, k };
                    let mut expected = initial.clone();
                    for i in 0..m {
                        for j in 0..n {
                            let mut sum = match start {
                                Start::Zero => 0.0f32,
                                Start::Bias(bias) => bias[j],
                                Start::Output => initial[i * n + j],
                            };
                            for p in 0..k {
                                sum = a.at(i, p).mul_add(b[p * n + j], sum);
                            }
                            expected[i * n + j] = sum;
                        }
                    }
                    let mut out = initial.clone();
                    product(&mut out, a, &b, m, n, k, start);
                    let mut results = vec![out];
                    #[cfg(target_arch = "x86_64")]
                    results.extend(x86::all_paths(&mut initial.clone(), a, &b, shape, start));
                    let mut portable_out = initial.clone();
                    portable(&mut portable_out, a, &b, shape, start);
                    results.push(portable_out);
                    for (path, result) in results.iter().enumerate() {
                        let same = result.iter().zip(&expected).all(|(x, y)| x.to_bits() == y.to_bits());
                        assert!(
                            same,
                            "path {path} differs from the rule at {m} x {n} x {k}, {start:?}, transposed {transposed}"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_fused_chain_is_not_a_sum_of_rounded_products() {
        // The rule is observable: with these values a separate multiply and add rounds differently.
        let (a, b) = ([1.0 + f32::EPSILON], [1.0 - f32::EPSILON]);
        let mut c = [-1.0f32];
        product(&mut c, Strided::rows(&a, 1), &b, 1, 1, 1, Start::Output);
        assert_eq!(c[0], -f32::EPSILON * f32::EPSILON, "one rounding, as fma");
        assert_eq!(a[0] * b[0] - 1.0, 0.0, "two roundings lose it");
    }

    #[test]
    fn paths_are_named_and_ordered_by_width() {
        for simd in [Simd::Avx512, Simd::Avx2, Simd::Portable] {
            assert_eq!(Simd::from_name(simd.name()), Some(simd));
        }
        assert_eq!(Simd::from_name(" AVX2 "), Some(Simd::Avx2));
        assert_eq!(Simd::from_name("sse"), None);
        assert!(Simd::active().lanes() <= Simd::widest().lanes());
    }
}
