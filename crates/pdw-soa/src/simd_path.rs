//! Which vector instructions the kernel's lane loops and `wide`'s `f64x4` run on, for the
//! provenance of every file written. Today the path is fixed when the crate is compiled (by
//! `-C target-cpu`, see `.cargo/config.toml`); a run-time dispatch will report its choice here.

/// The vector path as text, e.g. `"compile-time: avx512f+avx2+fma"`, `"compile-time: sse2"`,
/// `"compile-time: neon"`, or `"compile-time: scalar"`.
pub fn simd_path() -> String {
    let features: Vec<&str> = [
        ("avx512f", cfg!(target_feature = "avx512f")),
        ("avx2", cfg!(target_feature = "avx2")),
        ("avx", cfg!(target_feature = "avx")),
        ("fma", cfg!(target_feature = "fma")),
        ("sse4.1", cfg!(target_feature = "sse4.1")),
        ("sse2", cfg!(target_feature = "sse2")),
        ("neon", cfg!(target_feature = "neon")),
        ("simd128", cfg!(target_feature = "simd128")),
    ]
    .into_iter()
    .filter(|(_, on)| *on)
    .map(|(n, _)| n)
    .collect();
    if features.is_empty() {
        "compile-time: scalar".into()
    } else {
        format!("compile-time: {}", features.join("+"))
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn simd_path_names_the_compiled_features() {
        let p = super::simd_path();
        assert!(p.starts_with("compile-time: "), "{p}");
        // x86-64 always has SSE2; the path must say so (or something wider).
        if cfg!(target_arch = "x86_64") {
            assert!(p.contains("sse2"), "{p}");
        }
        assert_eq!(p.contains("avx2"), cfg!(target_feature = "avx2"), "{p}");
    }
}
