//! `specula plan`: the plan a scene gets — per specular object its method and why, its
//! reference point, maps with sizes and memory, passes and the knobs in force — as a table,
//! or as JSON with `--json`.

use crate::args::{prepare, RenderArgs};
use crate::budget::BudgetArgs;

pub fn run(args: &RenderArgs, json: bool, candidates: bool, budget: &BudgetArgs) -> specula::Result<()> {
    let mut job = prepare(args)?;
    if candidates {
        print_candidates(&job)?;
    }
    let prediction = crate::budget::apply(&mut job, &args.scene, budget)?;
    let p = job.plan(&job.quality)?;
    if json {
        // The plan, with how each object shows in the view of another that sees it.
        let mut plan = serde_json::to_value(&p).map_err(|e| specula::Error::invalid("plan", e.to_string()))?;
        plan["in_view"] = serde_json::json!(specula::plan::in_view(&p, &job.scene));
        let value = serde_json::json!({ "plan": plan, "prediction": &prediction });
        let text = serde_json::to_string_pretty(if prediction.is_some() { &value } else { &value["plan"] })
            .map_err(|e| specula::Error::invalid("plan", e.to_string()))?;
        println!("{text}");
    } else {
        if let Some(pr) = &prediction {
            println!("{}", specula::plan::budget::report(pr, None));
        }
        print!("{}", specula::plan::table(&p, &job.scene));
    }
    Ok(())
}

/// `--candidates`: per object the Pareto set of (predicted ms, predicted dB) the planner
/// chose from.
fn print_candidates(job: &crate::args::Job) -> specula::Result<()> {
    use specula::plan::predict;
    let Some(t) = job.target() else {
        return Err(specula::Error::invalid("--candidates", "no unit costs: run specula calibrate"));
    };
    let facts = specula::plan::facts::SceneFacts::new(&job.scene, &job.quality, true);
    let models = predict::predict_models(&job.scene, &facts, &job.quality, &t, &predict::auto_variants(&job.quality))?;
    println!("candidates at {}x{}, {}:", t.size.0, t.size.1, predict::source(&t));
    for (name, front, dominated) in predict::pareto(&models) {
        println!("{name}: {} on the Pareto front, {dominated} dominated", front.len());
        for (knobs, o) in front {
            let ms = o.cost.fixed_ms + o.cost.screen_ms + o.shared.screen_ms;
            println!(
                "  {:<24} {:<14} {:>10.2} ms {:>8.1} dB   (maps {:.2} ms, camera {:.2} ms, whole-screen {:.2} ms)",
                o.method, knobs, ms, o.psnr_db, o.cost.fixed_ms, o.cost.screen_ms, o.shared.screen_ms
            );
        }
    }
    println!();
    Ok(())
}
