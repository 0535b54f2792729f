//! The README's method table and docs/knobs.md's knob table are generated from the registry
//! and the knob table (`specula::docs`): every method with its C ABI name, section and the
//! objects it serves, every knob with its values (range and unit), default and the methods
//! that read it. A stale table fails; `SPECULA_UPDATE_README=1 cargo test --test readme`
//! rewrites them in place. The README stays a user's guide: under 300 lines.

#[test]
fn readme_tables_are_the_registry() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/README.md");
    let readme = std::fs::read_to_string(path).unwrap();
    let updated = specula::docs::splice(&readme, "methods", &specula::docs::method_table()).expect("README has the methods markers");
    let knobs_path = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/knobs.md");
    let knobs = std::fs::read_to_string(knobs_path).unwrap();
    let knobs_updated = specula::docs::splice(&knobs, "knobs", &specula::docs::knob_table()).expect("docs/knobs.md has the knobs markers");
    if std::env::var_os("SPECULA_UPDATE_README").is_some() {
        std::fs::write(path, &updated).unwrap();
        std::fs::write(knobs_path, &knobs_updated).unwrap();
    }
    assert!(readme == updated && knobs == knobs_updated, "README tables are stale: run SPECULA_UPDATE_README=1 cargo test --test readme");
    assert!(readme.lines().count() < 300, "the README is a user's guide: {} lines, under 300", readme.lines().count());
    for m in specula::Method::ALL {
        assert!(
            readme.contains(&format!("| `{}` | `SPECULA_METHOD_{}` |", m.name(), specula::docs::abi_name(*m))),
            "README lacks {}",
            m.name()
        );
    }
    for k in specula::quality::KNOBS {
        let row = knobs
            .lines()
            .find(|l| l.starts_with(&format!("| `{}` |", k.name)))
            .unwrap_or_else(|| panic!("docs/knobs.md lacks knob {}", k.name));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(
            (cells[2].to_string(), cells[3]),
            (specula::docs::cell(k.values), k.default),
            "docs/knobs.md range and default of {}",
            k.name
        );
    }
}
