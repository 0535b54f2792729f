//! `specula plan`: the plan a scene gets — per specular object its method and why, its
//! reference point, maps with sizes and memory, passes and the knobs in force — as a table,
//! or as JSON with `--json`.

use crate::args::{prepare, RenderArgs};

pub fn run(args: &RenderArgs, json: bool) -> specula::Result<()> {
    let job = prepare(args)?;
    let p = job.plan(&job.quality)?;
    if json {
        let text = serde_json::to_string_pretty(&p).map_err(|e| specula::Error::invalid("plan", e.to_string()))?;
        println!("{text}");
    } else {
        print!("{}", specula::plan::table(&p, &job.scene));
    }
    Ok(())
}
