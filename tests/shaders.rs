//! Every SPIR-V module that build.rs embedded passes `spirv-val` for Vulkan 1.3.

#[test]
fn every_embedded_module_validates() {
    assert!(specula::shaders::ALL.len() >= 7, "shaders were embedded");
    let dir = std::env::temp_dir().join(format!("specula-spirv-{}", std::process::id()));
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
