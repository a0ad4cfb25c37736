//! Which CPU trained a stage. Training computes the same bits on every x86-64 CPU with AVX2 and FMA
//! (`flapper_ppo::fixed_matmul`); each stage still records its CPU in `selected.json`, so that a run that
//! does not reproduce somewhere names the two machines (and runs from before the fixed arithmetic say
//! where they were trained).

/// The CPU as `brand (family F, model M; avx512f)`: the brand string, the family and model numbers that
/// tell its generation apart, and whether it has AVX-512 (the widest vector path). `None` off x86.
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
