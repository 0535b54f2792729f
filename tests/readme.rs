//! The README's method and knob tables are generated from the registry and the knob table
//! (`specula::docs`): every method with its C ABI name, section and the objects it serves,
//! every knob with its values (range and unit), default and the methods that read it. A
//! stale README fails; `SPECULA_UPDATE_README=1 cargo test --test readme` rewrites the
//! tables in place.

#[test]
fn readme_tables_are_the_registry() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/README.md");
    let readme = std::fs::read_to_string(path).unwrap();
    let updated = specula::docs::splice(&readme, "methods", &specula::docs::method_table()).expect("README has the methods markers");
    let updated = specula::docs::splice(&updated, "knobs", &specula::docs::knob_table()).expect("README has the knobs markers");
    if std::env::var_os("SPECULA_UPDATE_README").is_some() {
        std::fs::write(path, &updated).unwrap();
    }
    assert!(readme == updated, "README tables are stale: run SPECULA_UPDATE_README=1 cargo test --test readme");
    for m in specula::Method::ALL {
        assert!(
            readme.contains(&format!("| `{}` | `SPECULA_METHOD_{}` |", m.name(), specula::docs::abi_name(*m))),
            "README lacks {}",
            m.name()
        );
    }
    for k in specula::quality::KNOBS {
        let row =
            readme.lines().find(|l| l.starts_with(&format!("| `{}` |", k.name))).unwrap_or_else(|| panic!("README lacks knob {}", k.name));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!((cells[2].to_string(), cells[3]), (specula::docs::cell(k.values), k.default), "README range and default of {}", k.name);
    }
}
