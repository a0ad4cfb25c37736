//! Standard normal draws for the exploration noise, in pure Rust arithmetic (Marsaglia's polar method
//! on `libm`'s log): the same numbers from the same stream on every CPU and C library. (`rand_distr`'s
//! ziggurat calls the platform's `exp` and `log`, whose last bits may differ between libraries.)

use rand::Rng;

/// One draw from N(0, 1).
pub fn standard_normal(rng: &mut impl Rng) -> f32 {
    loop {
        let u = 2.0 * rng.random::<f64>() - 1.0;
        let v = 2.0 * rng.random::<f64>() - 1.0;
        let s = u * u + v * v;
        if s > 0.0 && s < 1.0 {
            return (u * (-2.0 * libm::log(s) / s).sqrt()) as f32;
        }
    }
}

#[cfg(test)]
mod tests {
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    use super::*;

    #[test]
    fn draws_have_the_moments_and_tails_of_a_standard_normal() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let n = 200_000;
        let draws: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng) as f64).collect();
        let mean = draws.iter().sum::<f64>() / n as f64;
        let var = draws.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n as f64;
        let kurtosis = draws.iter().map(|x| (x - mean).powi(4)).sum::<f64>() / n as f64 / (var * var);
        assert!(mean.abs() < 0.01, "mean {mean}");
        assert!((var - 1.0).abs() < 0.01, "variance {var}");
        assert!((kurtosis - 3.0).abs() < 0.05, "kurtosis {kurtosis}");
        // P(|x| > 2) = 4.55%, P(|x| > 3) = 0.27%.
        let beyond = |t: f64| draws.iter().filter(|x| x.abs() > t).count() as f64 / n as f64;
        assert!((beyond(2.0) - 0.0455).abs() < 0.002, "{}", beyond(2.0));
        assert!((beyond(3.0) - 0.0027).abs() < 0.0005, "{}", beyond(3.0));
    }
}
