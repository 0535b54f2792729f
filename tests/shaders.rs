//! Every SPIR-V module that build.rs embedded passes `spirv-val` for Vulkan 1.3.

#[test]
fn every_embedded_module_validates() {
    // Every shader source under glsl/ (not the headers in common/) and every variant it
    // declares is embedded, and nothing else.
    let root = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/glsl"));
    let mut expected = Vec::new();
    let mut stack = vec![root.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                if p.file_name().is_some_and(|n| n != "common") {
                    stack.push(p);
                }
            } else if p.extension().and_then(|x| x.to_str()).is_some_and(|x| ["vert", "frag", "comp", "geom", "tesc", "tese"].contains(&x))
            {
                let name = p.strip_prefix(root).unwrap().to_string_lossy().replace('\\', "/");
                let text = std::fs::read_to_string(&p).unwrap();
                for v in text.lines().take(12).filter_map(|l| l.trim().strip_prefix("// variants:")).flat_map(|v| v.split_whitespace()) {
                    expected.push(format!("{name}#{v}"));
                }
                expected.push(name);
            }
        }
    }
    expected.sort();
    let mut embedded: Vec<String> = specula::shaders::ALL.iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(embedded, expected, "embedded modules vs glsl/ sources");
    assert!(embedded.len() > 40, "{} modules", embedded.len());
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-spirv-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in specula::shaders::ALL {
        assert_eq!(&bytes[..4], &0x0723_0203u32.to_le_bytes(), "{name}: SPIR-V magic");
        let path = dir.join(name.replace('/', "__") + ".spv");
        std::fs::write(&path, bytes).unwrap();
        let out = std::process::Command::new("spirv-val")
            .args(["--target-env", "vulkan1.3"])
            .arg(&path)
            .output()
            .expect("spirv-val not found: apt-get install spirv-tools");
        assert!(out.status.success(), "{name}: {}{}", String::from_utf8_lossy(&out.stdout), String::from_utf8_lossy(&out.stderr));
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn shaders_are_found_by_name() {
    assert!(specula::shaders::get("envmap/shade.frag").is_some());
    assert!(specula::shaders::get("common/optics.glsl").is_none(), "headers are not modules");
}
