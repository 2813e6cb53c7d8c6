//! What a test does when something it needs is missing: it **fails**, with a message that says
//! what to install. The same command fails the same way on every machine; whether `CI` is set
//! does not matter.
//!
//! A developer on a machine without one of the requirements opts out explicitly, naming it:
//! `SPECULA_ALLOW_SKIP=gpu,xvfb,mpi,corpus,avx,browser` (any subset, comma-separated; each word trimmed,
//! case ignored: [`allowed`], the rule scripts/allow-skip.sh applies too). A test skipped that way
//! returns early and appends one line, `requirement<TAB>test<TAB>why`, to the file named by
//! `SPECULA_SKIP_LOG` (scripts/test.sh names one and prints how many tests were skipped, per
//! requirement, at the end), so a skip is never silent.

use std::io::Write;

/// The environment variable that lists the requirements a run may do without.
pub const ALLOW_SKIP: &str = "SPECULA_ALLOW_SKIP";
/// The environment variable naming the file each skip is appended to.
pub const SKIP_LOG: &str = "SPECULA_SKIP_LOG";

/// Something outside the Rust build that a test needs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Requirement {
    /// A Vulkan adapter (Mesa's lavapipe where there is no GPU).
    Gpu,
    /// `xvfb-run`, for the viewer's window.
    Xvfb,
    /// `mpirun`, for distributed vertex tracing.
    Mpi,
    /// Debian's `assimp-testmodels` corpus of real and malformed model files.
    Corpus,
    /// A CPU with AVX, for the ray kernel's AVX traversal.
    Avx,
    /// Debian's headless `chromium`, to open the HTML reports in a real browser.
    Browser,
}

impl Requirement {
    pub const ALL: [Requirement; 6] = [
        Requirement::Gpu,
        Requirement::Xvfb,
        Requirement::Mpi,
        Requirement::Corpus,
        Requirement::Avx,
        Requirement::Browser,
    ];

    /// The word `SPECULA_ALLOW_SKIP` and the skip log use.
    pub fn key(self) -> &'static str {
        match self {
            Requirement::Gpu => "gpu",
            Requirement::Xvfb => "xvfb",
            Requirement::Mpi => "mpi",
            Requirement::Corpus => "corpus",
            Requirement::Avx => "avx",
            Requirement::Browser => "browser",
        }
    }

    /// What brings it.
    pub fn install(self) -> &'static str {
        match self {
            Requirement::Gpu => "apt-get install mesa-vulkan-drivers libvulkan1",
            Requirement::Xvfb => "apt-get install xvfb xauth",
            Requirement::Mpi => "apt-get install openmpi-bin libopenmpi-dev libclang-dev",
            Requirement::Corpus => "apt-get install assimp-testmodels",
            Requirement::Avx => "an x86-64 CPU with AVX (no package brings it)",
            Requirement::Browser => "apt-get install chromium",
        }
    }
}

/// Whether `allow` (the value of `SPECULA_ALLOW_SKIP`) names `requirement`.
pub fn allowed(allow: Option<&str>, requirement: Requirement) -> bool {
    allow.is_some_and(|list| {
        list.split(',')
            .any(|word| word.trim().eq_ignore_ascii_case(requirement.key()))
    })
}

/// The failure message for `test` missing `requirement` (`why`: what was found), or `None`
/// where `allow` (the value of `SPECULA_ALLOW_SKIP`) names the requirement.
pub fn failure(
    allow: Option<&str>,
    requirement: Requirement,
    test: &str,
    why: &str,
) -> Option<String> {
    (!allowed(allow, requirement)).then(|| {
        format!(
            "{test}: needs {} and it is missing ({why}). Install it (`{}`, or run scripts/setup.sh), \
             or opt out explicitly with {ALLOW_SKIP}={}",
            requirement.key(),
            requirement.install(),
            requirement.key()
        )
    })
}

/// Called by `test` when `requirement` is missing (`why`: what was found). Panics with what to
/// install, unless `SPECULA_ALLOW_SKIP` names the requirement: then the skip is logged (stderr
/// and `SPECULA_SKIP_LOG`) and the function returns, and the test must return at once.
pub fn missing(requirement: Requirement, test: &str, why: &str) {
    let allow = std::env::var(ALLOW_SKIP).ok();
    if let Some(message) = failure(allow.as_deref(), requirement, test, why) {
        panic!("{message}");
    }
    eprintln!(
        "SKIPPED {test}: no {} ({why}); allowed by {ALLOW_SKIP}",
        requirement.key()
    );
    if let Some(path) = std::env::var_os(SKIP_LOG) {
        // libtest names each test's thread after the test: a test that checks a requirement
        // several times is still one skipped test.
        let current = std::thread::current();
        let name = current.name().filter(|n| *n != "main").unwrap_or(test);
        let line = format!(
            "{}\t{name}\t{}\n",
            requirement.key(),
            why.replace('\n', " ")
        );
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .and_then(|mut file| file.write_all(line.as_bytes()));
        if let Err(e) = appended {
            panic!(
                "{test}: skipped, but the skip could not be logged to {}: {e}",
                std::path::Path::new(&path).display()
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_a_named_requirement_may_be_skipped() {
        assert!(!allowed(None, Requirement::Gpu));
        assert!(!allowed(Some(""), Requirement::Gpu));
        assert!(!allowed(Some("xvfb,mpi"), Requirement::Gpu));
        assert!(allowed(Some("xvfb, GPU"), Requirement::Gpu));
        assert!(!allowed(Some("gpus"), Requirement::Gpu));
        for requirement in Requirement::ALL {
            assert!(allowed(
                Some("gpu,xvfb,mpi,corpus,avx,browser"),
                requirement
            ));
        }
    }

    /// scripts/allow-skip.sh (what setup.sh and test.sh decide by) reads SPECULA_ALLOW_SKIP
    /// exactly as [`allowed`] does: one rule, whichever side reads it.
    #[test]
    fn the_scripts_read_the_skip_list_by_the_same_rule() {
        let script =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scripts/allow-skip.sh");
        let lists = [
            "",
            ",",
            "gpu",
            "GPU",
            " gpu ",
            "gpus",
            "xgpu",
            "gpu,",
            ",gpu",
            "xvfb,mpi",
            "xvfb, Mpi",
            "corpus\t,avx",
            "\tcorpus",
            "gpu xvfb",
            "gpu;mpi",
            "*",
            "gpu,*,mpi",
            "mpi,,avx",
        ];
        for list in lists {
            for requirement in Requirement::ALL {
                let status = std::process::Command::new("bash")
                    .arg("-c")
                    .arg(format!(
                        "source '{}' && specula_allowed {}",
                        script.display(),
                        requirement.key()
                    ))
                    .env(ALLOW_SKIP, list)
                    .status()
                    .expect("bash runs");
                assert_eq!(
                    status.success(),
                    allowed(Some(list), requirement),
                    "SPECULA_ALLOW_SKIP={list:?}, {}",
                    requirement.key()
                );
            }
        }
    }

    #[test]
    fn a_missing_requirement_fails_with_what_to_install_unless_named() {
        let message = failure(None, Requirement::Mpi, "t", "no mpirun on PATH").unwrap();
        assert!(message.contains("needs mpi"), "{message}");
        assert!(message.contains("apt-get install openmpi-bin"), "{message}");
        assert!(message.contains("SPECULA_ALLOW_SKIP=mpi"), "{message}");
        assert!(failure(Some("gpu"), Requirement::Mpi, "t", "").is_some());
        assert!(failure(Some("gpu,mpi"), Requirement::Mpi, "t", "").is_none());
    }
}
