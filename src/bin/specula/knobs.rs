//! `specula knobs`: methods (with their C ABI numbers, sections, the objects they serve and
//! the knobs they read) and accuracy knobs with their ranges and defaults, from the
//! registry and the knob table.

use specula::Method;

pub fn run() -> specula::Result<()> {
    println!("methods: auto, {}", Method::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "));
    println!("\n{:<24} {:>4}  {:<12} {:<36} knobs", "method", "C", "survey", "serves");
    println!("{:<24} {:>4}  {:<12} {:<36} planner", "auto", specula::methods::registry::ABI_AUTO, "", "any");
    for m in Method::ALL {
        let serves: Vec<&str> = m.serves.iter().map(|c| c.label()).collect();
        println!("{:<24} {:>4}  {:<12} {:<36} {}", m.name, m.abi, m.section, serves.join(", "), m.knobs.join(" "));
    }
    println!("\n{:<20} {:<22} {:<9} description", "knob", "values", "default");
    for k in specula::quality::KNOBS {
        println!("{:<20} {:<22} {:<9} {}", k.name, k.values, k.default, k.doc);
    }
    Ok(())
}
