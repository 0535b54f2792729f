//! `specula plan`: the plan a scene gets, as JSON.

use crate::args::{prepare, RenderArgs};

pub fn run(args: &RenderArgs) -> specula::Result<()> {
    let job = prepare(args)?;
    let p = specula::plan(&job.scene, job.method, &job.quality);
    println!("{}", serde_json::to_string_pretty(&p).unwrap_or_default());
    Ok(())
}
