//! Which CPU trained a stage. Training is deterministic on one CPU model but not across them: `gemm`
//! picks its kernels and block sizes from the CPU, and the sums of the update come out grouped
//! differently (docs/experiments.md, "training across CPU models"). Each stage records its CPU in
//! `selected.json`, so that whoever re-runs it knows which machine reproduces it row for row.

/// The CPU as `brand (family F, model M; avx512f)`: the brand string, the family and model numbers that
/// tell its generation apart, and whether it has AVX-512 (`gemm`'s widest kernels). `None` off x86.
pub fn cpu_model() -> Option<String> {
    #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
    {
        let cpuid = raw_cpuid::CpuId::new();
        let brand = cpuid.get_processor_brand_string().map(|b| b.as_str().trim().to_owned());
        let (family, model) = cpuid.get_feature_info().map_or((0, 0), |f| (f.family_id(), f.model_id()));
        let avx512 = cpuid.get_extended_feature_info().is_some_and(|f| f.has_avx512f());
        Some(format!(
            "{} (family {family}, model {model}; {})",
            brand.as_deref().unwrap_or("unknown x86 CPU"),
            if avx512 { "avx512f" } else { "no avx512f" }
        ))
    }
    #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
    {
        None
    }
}
