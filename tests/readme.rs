//! The README's tables name every method and every knob the code has, with the code's
//! defaults (the code is the one place they are written; this keeps the prose honest).

#[test]
fn readme_lists_every_method_and_knob() {
    let readme = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    for m in specula::Method::ALL {
        assert!(readme.contains(&format!("| `{}` |", m.name())), "README lacks method {}", m.name());
    }
    for k in specula::quality::KNOBS {
        let row =
            readme.lines().find(|l| l.starts_with(&format!("| `{}` |", k.name))).unwrap_or_else(|| panic!("README lacks knob {}", k.name));
        let cells: Vec<&str> = row.split('|').map(str::trim).collect();
        assert_eq!(cells[3], k.default, "README default of {}", k.name);
    }
}
