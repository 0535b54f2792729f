//! `specula plan`: the plan a scene gets — per specular object its method and why, its
//! reference point, maps with sizes and memory, passes and the knobs in force — as a table,
//! or as JSON with `--json`.

use crate::args::{prepare, RenderArgs};
use crate::budget::BudgetArgs;

pub fn run(args: &RenderArgs, json: bool, budget: &BudgetArgs) -> specula::Result<()> {
    let mut job = prepare(args)?;
    let prediction = crate::budget::apply(&mut job, &args.scene, budget)?;
    let p = job.plan(&job.quality)?;
    if json {
        let value = serde_json::json!({ "plan": &p, "prediction": &prediction });
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
