//! `specula knobs`: methods and accuracy knobs with their ranges and defaults.

use specula::Method;

pub fn run() -> specula::Result<()> {
    println!("methods: {}", Method::ALL.iter().map(|m| m.name()).collect::<Vec<_>>().join(", "));
    println!("\n{:<20} {:<22} {:<9} description", "knob", "values", "default");
    for k in specula::quality::KNOBS {
        println!("{:<20} {:<22} {:<9} {}", k.name, k.values, k.default, k.doc);
    }
    Ok(())
}
