//! Which kernels the structures use: forced (`--isa`, the `RAYLAB_ISA` variable) or measured
//! ([`calibrate`](super::calibrate)), decided once per process.

use std::sync::OnceLock;

use super::calibrate::{self, Calibration};
use super::isa::Isa;

/// The kernels every structure uses unless told otherwise: forced ([`Isa::force`], the
/// `RAYLAB_ISA` variable) or measured ([`calibrate`]), once per process.
static CHOSEN: OnceLock<(Isa, Option<Calibration>)> = OnceLock::new();

impl Isa {
    /// The kernels to use on this CPU: the one forced by `--isa` ([`Isa::force`]) or the
    /// `RAYLAB_ISA` environment variable (`avx512`, `avx2` or `scalar`, if this CPU runs it),
    /// else the fastest on `workloads` ([`calibrate::calibrate`]: not always the widest; the
    /// renderer's workloads come from `scene::best_isa`). Decided once per process: later calls
    /// return the same set without calling `workloads`.
    pub fn best_with(workloads: impl FnOnce() -> Vec<calibrate::Workload>) -> Self {
        Self::chosen(workloads).0
    }

    /// What [`Isa::best_with`] measured, if it has measured (not when forced).
    pub fn calibration() -> Option<&'static Calibration> {
        CHOSEN.get().and_then(|(_, c)| c.as_ref())
    }

    fn chosen(
        workloads: impl FnOnce() -> Vec<calibrate::Workload>,
    ) -> &'static (Isa, Option<Calibration>) {
        CHOSEN.get_or_init(|| {
            let forced = std::env::var("RAYLAB_ISA").ok();
            match forced.as_deref().and_then(Isa::by_name) {
                Some(isa) => (isa, None),
                None => {
                    let c = calibrate::calibrate(&workloads());
                    (c.chosen, Some(c))
                }
            }
        })
    }

    /// Makes `self` the kernels of every structure built from now on (`--isa`). Fails if
    /// [`Isa::best_with`] has already decided on another set in this process.
    pub fn force(self) -> Result<(), String> {
        let (chosen, _) = CHOSEN.get_or_init(|| (self, None));
        if chosen.name() == self.name() {
            Ok(())
        } else {
            Err(format!(
                "the kernels were already chosen ({}) before --isa {}",
                chosen.name(),
                self.name()
            ))
        }
    }

    /// What is wrong with the `RAYLAB_ISA` environment variable, when it is set to something
    /// [`Isa::best_with`] cannot use and so does not (it measures, as if the variable were
    /// unset): for a warning naming the sets that are accepted. `None` when it is unset, `best`
    /// or a set this CPU runs.
    pub fn environment_note() -> Option<String> {
        let value = std::env::var_os("RAYLAB_ISA")?;
        let text = value.to_string_lossy();
        if text == "best" || Isa::by_name(&text).is_some() {
            return None;
        }
        let known = ["avx512", "avx2", "scalar"].contains(&&*text);
        let runs: Vec<&str> = Isa::available().iter().rev().map(|i| i.name()).collect();
        Some(format!(
            "RAYLAB_ISA={text:?} is {}: the kernels are chosen by measuring, as without it \
             (accepted: best, {})",
            if known {
                "a kernel set this CPU does not run"
            } else {
                "not a kernel set"
            },
            runs.join(", ")
        ))
    }
}
