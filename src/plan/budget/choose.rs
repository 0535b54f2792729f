//! The budgeted choice: the best of every variant's search and whole-scene rows.

use super::candidates::{candidates, Candidate};
use super::search::{better, combined_psnr, rank, search, Timing};
use super::{variant_quality, Budget, Models, ObjectPrediction, Prediction};
use crate::error::Result;
use crate::plan::facts::SceneFacts;
use crate::plan::{Choices, Method};
use crate::quality::Quality;
use crate::scene::Scene;

/// The budgeted plan: per object a method and the frame's knobs from the first models set
/// (in `sources`: (models, where from)) that covers every specular object, with its
/// prediction; `None` when none covers them (the caller falls back to the registry's rules
/// and says so). The objects the user forced (`choices.objects`) keep their method; a choice
/// of one method for every object is returned as that whole-scene method.
pub fn choose(
    scene: &Scene,
    choices: &Choices,
    quality: &Quality,
    budget: Budget,
    size: (u32, u32),
    sources: &[(&Models, String)],
) -> Result<Option<(Choices, Quality, Prediction)>> {
    choose_with(scene, &SceneFacts::new(scene, quality, true), choices, quality, budget, size, sources)
}

/// [`choose`] with the scene's (deep) facts already computed.
pub fn choose_with(
    scene: &Scene,
    facts: &SceneFacts,
    choices: &Choices,
    quality: &Quality,
    budget: Budget,
    size: (u32, u32),
    sources: &[(&Models, String)],
) -> Result<Option<(Choices, Quality, Prediction)>> {
    if facts.objects.is_empty() {
        return Ok(None);
    }
    for (models, source) in sources {
        let Some(variants) = candidates(scene, facts, choices, models, size) else { continue };
        // (variant, whole-scene method or None for mixed, picks, rank)
        let mut best: Option<Best> = None;
        for (k, v) in variants.iter().enumerate() {
            let timing = Timing { base: v.base, quality: variant_quality(quality, &v.knobs)?, facts, sight: facts.sight() };
            let idx = search(budget, &|p| timing.frame_ms(p, false), &v.per_object);
            let mixed: Vec<Candidate> = idx.iter().zip(&v.per_object).map(|(&i, c)| c[i].clone()).collect();
            let options = std::iter::once((None, v.base, mixed)).chain(v.wholes.iter().map(|(m, b, list)| (Some(*m), *b, list.clone())));
            for (whole, base, picks) in options {
                let refs: Vec<&Candidate> = picks.iter().collect();
                let t = Timing { base, quality: timing.quality.clone(), facts, sight: timing.sight.clone() };
                let r = rank(budget, t.frame_ms(&refs, whole.is_some()), &refs);
                if best.as_ref().is_none_or(|b| better(r, b.4)) {
                    best = Some((k, whole, base, picks, r));
                }
            }
        }
        let Some((k, whole, base, picks, r)) = best else { continue };
        let v = &variants[k];
        let q = variant_quality(quality, &v.knobs)?;
        let timing = Timing { base, quality: q.clone(), facts, sight: facts.sight() };
        let refs: Vec<&Candidate> = picks.iter().collect();
        let objects: Vec<ObjectPrediction> = facts
            .objects
            .iter()
            .zip(&picks)
            .enumerate()
            .map(|(i, (f, c))| {
                let (maps_ms, camera_ms) = timing.object_parts(&refs, i, whole.is_some());
                ObjectPrediction {
                    mesh: f.mesh,
                    name: scene.meshes[f.mesh].name.clone(),
                    method: c.method,
                    ms: maps_ms + camera_ms,
                    maps_ms,
                    psnr_db: c.psnr,
                    pixels: c.pixels,
                    model: c.model.clone(),
                }
            })
            .collect();
        // A whole-scene method as the study ran it; one method everywhere (nothing forced)
        // planned the same way; otherwise per-object methods.
        let whole = whole.or_else(|| (Timing::uniform(&refs) && choices.objects.is_empty()).then(|| refs[0].method));
        let out = match whole {
            Some(m) => Choices::all(m),
            None => Choices { method: choices.method, objects: objects.iter().map(|o| (o.name.clone(), o.method)).collect() },
        };
        let prediction = Prediction {
            budget,
            knobs: v.knobs.clone(),
            base_ms: base,
            frame_ms: timing.frame_ms(&refs, whole.is_some()),
            specular_psnr_db: combined_psnr(&refs),
            objects,
            met: r.0,
            source: source.clone(),
            whole_scene: whole.map(|m| m.name.to_string()),
        };
        return Ok(Some((out, q, prediction)));
    }
    Ok(None)
}

/// The best variant so far: (variant, whole-scene method or None for mixed, predicted ms,
/// picks, rank).
type Best = (usize, Option<Method>, f64, Vec<Candidate>, (bool, f64, f64));
