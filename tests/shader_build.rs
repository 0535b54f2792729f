//! The shader build's error reporting: a broken shader fails with `file:line: message`.

#[path = "../build/shaderc.rs"]
#[allow(dead_code)]
mod shaderc;

#[test]
fn broken_shader_reports_file_and_line() {
    let root = std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("specula-shaderc-{}", std::process::id()));
    let glsl = root.join("glsl");
    std::fs::create_dir_all(glsl.join("common")).unwrap();
    std::fs::write(glsl.join("common/h.glsl"), "float helper() { return 1.0; }\n").unwrap();
    let bad = glsl.join("bad.frag");
    std::fs::write(
        &bad,
        "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"common/h.glsl\"\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(undeclared_thing); }\n",
    )
    .unwrap();
    let err = shaderc::compile("glslangValidator", &glsl, &root, &bad).unwrap_err();
    assert!(err.starts_with("glsl/bad.frag:5: "), "{err}");
    assert!(err.contains("undeclared_thing"), "{err}");

    let good = glsl.join("good.frag");
    std::fs::write(&good, "#version 460\n#extension GL_GOOGLE_include_directive : require\n#include \"common/h.glsl\"\nlayout(location = 0) out vec4 c;\nvoid main() { c = vec4(helper()); }\n").unwrap();
    let (name, spv) = shaderc::compile("glslangValidator", &glsl, &root, &good).unwrap();
    assert_eq!(name, "good.frag");
    assert!(std::fs::metadata(spv).unwrap().len() > 20);

    let mut found = Vec::new();
    shaderc::collect(&glsl, &mut found);
    assert_eq!(found.len(), 2, "headers under common/ are not compiled on their own: {found:?}");
    std::fs::remove_dir_all(&root).ok();
}
