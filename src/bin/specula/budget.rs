//! `--max-ms` / `--min-psnr` of `specula render` and `specula plan`: the budgeted planner
//! (`specula::plan::budget`) with the models of `--models`, of the file a calibration wrote
//! next to the scene, or the stored defaults; without models the registry's rules, said so.

use std::path::{Path, PathBuf};

use specula::plan::budget::{self, Budget, Models, Prediction};
use specula::Choice;

use crate::args::Job;

#[derive(clap::Args, Clone, Default)]
pub struct BudgetArgs {
    /// With --method auto: per object the method and the knobs that fit a frame of at most
    /// this many GPU milliseconds at the least predicted error (per-object models, see --models).
    #[arg(long)]
    pub max_ms: Option<f64>,
    /// With --method auto: every specular object at least this PSNR (dB) on its pixels, at the
    /// least predicted time.
    #[arg(long)]
    pub min_psnr: Option<f64>,
    /// Models from `specula tradeoff --calibrate` (default: SCENE.specula-models.json next to
    /// the scene if present, else the stored defaults measured on the bundled scenes).
    #[arg(long)]
    pub models: Option<PathBuf>,
}

/// Where `specula tradeoff --calibrate` writes a scene's models by default.
pub fn default_models_path(scene: &Path) -> PathBuf {
    scene.with_extension("specula-models.json")
}

/// Applies the budget to the job (its choices and knobs) and returns the prediction; `None`
/// without a budget. Without models that cover the scene: the registry's rules, said on stderr.
pub fn apply(job: &mut Job, scene_path: &Path, a: &BudgetArgs) -> specula::Result<Option<Prediction>> {
    let Some(b) = Budget::from_limits(a.max_ms, a.min_psnr)? else {
        if a.models.is_some() {
            return Err(specula::Error::invalid("--models", "needs --max-ms or --min-psnr"));
        }
        return Ok(None);
    };
    if job.choices.method != Choice::Auto {
        return Err(specula::Error::invalid(b.describe(), format!("needs --method auto (got '{}')", job.choices.method.name())));
    }
    let own = a.models.clone().or_else(|| Some(default_models_path(scene_path)).filter(|p| p.exists()));
    let chosen = match own {
        // A calibration of this very scene (specula tradeoff --calibrate).
        Some(p) => {
            let m = Models::load(&p)?;
            budget::choose(
                &job.scene,
                &job.choices,
                &job.quality,
                b,
                (job.width, job.height),
                &[(&m, format!("calibration {}", p.display()))],
            )?
        }
        // Predicted from the objects' facts and the device's unit costs.
        None => match job.target() {
            Some(t) => {
                specula::plan::predict::choose(&job.scene, &job.choices, &job.quality, b, &t, &specula::plan::predict::budget_variants())?
            }
            None => None,
        },
    };
    match chosen {
        Some((choices, quality, prediction)) => {
            job.choices = choices;
            job.quality = quality;
            Ok(Some(prediction))
        }
        None => {
            eprintln!(
                "specula: no prediction covers this scene's specular objects: auto without a budget chooses ({} ignored)",
                b.describe()
            );
            Ok(None)
        }
    }
}
