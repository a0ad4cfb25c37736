//! The system C compiler: compiling an exported policy with strict flags, and timing one call of it on
//! this CPU.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::DeployError;
use crate::c_source::FUNCTION;

/// ISO C99 with every warning an error and no fused multiply-adds: how the export is checked.
pub const STRICT_FLAGS: [&str; 7] =
    ["-std=c99", "-O2", "-Wall", "-Wextra", "-pedantic", "-Werror", "-ffp-contract=off"];

/// A C compiler that runs: `$CC`, else `cc`.
#[derive(Debug, Clone)]
pub struct CCompiler {
    program: String,
}

impl CCompiler {
    /// `$CC` or `cc`, if it runs (`--version`); `None` otherwise.
    pub fn find() -> Option<Self> {
        let program = std::env::var("CC").ok().filter(|p| !p.trim().is_empty()).unwrap_or_else(|| "cc".to_owned());
        let runs = Command::new(&program).arg("--version").output().is_ok_and(|o| o.status.success());
        runs.then_some(Self { program })
    }

    pub fn program(&self) -> &str {
        &self.program
    }

    /// The compiler's first line of `--version` (e.g. "cc (Debian 14.2.0-19) 14.2.0").
    pub fn version(&self) -> String {
        Command::new(&self.program)
            .arg("--version")
            .output()
            .ok()
            .and_then(|o| String::from_utf8_lossy(&o.stdout).lines().next().map(str::to_owned))
            .unwrap_or_default()
    }

    /// Compiles and links `sources` into the program `output` with [`STRICT_FLAGS`], headers from
    /// `include`. A failure names the compiler and quotes its first error.
    pub fn build(&self, sources: &[&Path], include: &Path, output: &Path) -> Result<(), DeployError> {
        let done = Command::new(&self.program)
            .args(STRICT_FLAGS)
            .arg("-I")
            .arg(include)
            .args(sources)
            .arg("-o")
            .arg(output)
            .arg("-lm")
            .output()
            .map_err(|e| DeployError::Compiler(format!("cannot run the C compiler '{}': {e}", self.program)))?;
        if !done.status.success() {
            let stderr = String::from_utf8_lossy(&done.stderr);
            let first =
                stderr.lines().find(|l| l.contains("error")).unwrap_or_else(|| stderr.lines().next().unwrap_or(""));
            return Err(DeployError::Compiler(format!(
                "'{} {}' failed: {}",
                self.program,
                STRICT_FLAGS.join(" "),
                first.trim()
            )));
        }
        Ok(())
    }
}

/// Times one call of the exported function: `calls` calls per round, the median round of `rounds`.
const TIMING: &str = r#"#define _POSIX_C_SOURCE 199309L
#include <stdio.h>
#include <time.h>
#include "HEADER"

static double now_s(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

int main(void) {
    static float obs[FLAPPER_POLICY_OBSERVATION_SIZE];
    float actions[FLAPPER_POLICY_ACTION_SIZE];
    double rounds[ROUNDS], t;
    volatile float sink = 0.0f;
    int i, r, k;
    for (i = 0; i < FLAPPER_POLICY_OBSERVATION_SIZE; i++) obs[i] = 0.01f * (float)(i % 23) - 0.1f;
    for (k = 0; k < CALLS; k++) FUNCTION(obs, actions);
    for (r = 0; r < ROUNDS; r++) {
        t = now_s();
        for (k = 0; k < CALLS; k++) {
            obs[k % FLAPPER_POLICY_OBSERVATION_SIZE] += 1e-6f;
            FUNCTION(obs, actions);
            sink += actions[0];
        }
        rounds[r] = (now_s() - t) / CALLS;
    }
    for (r = 1; r < ROUNDS; r++) {
        for (k = r; k > 0 && rounds[k - 1] > rounds[k]; k--) {
            t = rounds[k]; rounds[k] = rounds[k - 1]; rounds[k - 1] = t;
        }
    }
    printf("%.3f\n", rounds[ROUNDS / 2] * 1e6);
    return sink == 12345.0f;
}
"#;

/// What timing the exported C found.
#[derive(Debug, Clone, PartialEq)]
pub struct Latency {
    /// The median over rounds of one call's time (microseconds).
    pub per_call_us: f64,
    pub compiler: String,
    pub flags: String,
}

/// Compiles `source` (its header `header` beside it) with a timing harness in a scratch folder under
/// `scratch`, runs it and returns one call's median time on this CPU.
pub fn time_policy(compiler: &CCompiler, source: &Path, header: &Path, scratch: &Path) -> Result<Latency, DeployError> {
    let folder = scratch.join(format!("flapper-c-timing-{}", std::process::id()));
    std::fs::create_dir_all(&folder).map_err(|source| DeployError::Write { path: folder.clone(), source })?;
    let result = (|| {
        let header_name = header.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let harness = TIMING
            .replace("HEADER", &header_name)
            .replace("FUNCTION", FUNCTION)
            .replace("ROUNDS", "7")
            .replace("CALLS", "400");
        let harness_path = folder.join("timing.c");
        std::fs::write(&harness_path, harness)
            .map_err(|source| DeployError::Write { path: harness_path.clone(), source })?;
        let program: PathBuf = folder.join("timing");
        let include = header.parent().filter(|p| !p.as_os_str().is_empty()).unwrap_or(Path::new("."));
        compiler.build(&[source, &harness_path], include, &program)?;
        let done = Command::new(&program)
            .output()
            .map_err(|e| DeployError::Compiler(format!("cannot run the timing program: {e}")))?;
        let text = String::from_utf8_lossy(&done.stdout);
        let per_call_us = text
            .trim()
            .parse::<f64>()
            .map_err(|_| DeployError::Compiler(format!("the timing program printed '{}'", text.trim())))?;
        Ok(Latency { per_call_us, compiler: compiler.version(), flags: STRICT_FLAGS.join(" ") })
    })();
    let _ = std::fs::remove_dir_all(&folder);
    result
}
