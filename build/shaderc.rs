//! The shader compiler driver, shared by build.rs and the tests (`tests/shader_build.rs`):
//! runs `glslangValidator` on one file and turns its diagnostics into `file:line: message`.

use std::path::{Path, PathBuf};
use std::process::Command;

pub const STAGES: &[&str] = &["vert", "frag", "comp", "geom", "tesc", "tese"];

pub fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            if p.file_name().is_some_and(|n| n != "common") {
                collect(&p, out);
            }
        } else if p.extension().and_then(|x| x.to_str()).is_some_and(|x| STAGES.contains(&x)) {
            out.push(p);
        }
    }
}

/// Compiles one shader; on failure returns its diagnostics as `file:line: message`.
pub fn compile(compiler: &str, glsl: &Path, out: &Path, src: &Path) -> Result<(String, PathBuf), String> {
    compile_with(compiler, glsl, &[], out, src)
}

/// `compile`, with more include directories searched after `glsl` (build.rs: the generated
/// headers in `$OUT_DIR/glsl`).
pub fn compile_with(compiler: &str, glsl: &Path, includes: &[&Path], out: &Path, src: &Path) -> Result<(String, PathBuf), String> {
    compile_variant(compiler, glsl, includes, out, src, None)
}

/// The variants a shader declares on a line `// variants: NAME …` among its first lines:
/// each is compiled again with `-DNAME`, embedded as `path#NAME`.
pub fn variants(src: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(src).unwrap_or_default();
    text.lines()
        .take(12)
        .filter_map(|l| l.trim().strip_prefix("// variants:"))
        .flat_map(|v| v.split_whitespace().map(str::to_string).collect::<Vec<_>>())
        .collect()
}

/// `compile_with`, with the preprocessor symbol `variant` defined (named `path#VARIANT`).
pub fn compile_variant(
    compiler: &str,
    glsl: &Path,
    includes: &[&Path],
    out: &Path,
    src: &Path,
    variant: Option<&str>,
) -> Result<(String, PathBuf), String> {
    let mut name = src.strip_prefix(glsl).unwrap().to_string_lossy().replace('\\', "/");
    if let Some(v) = variant {
        name = format!("{name}#{v}");
    }
    let spv = out.join(format!("{}.spv", name.replace('/', "__").replace('#', "__variant_")));
    let output = Command::new(compiler)
        .args(["-V", "--target-env", "vulkan1.3", "-Os"])
        .args(variant.map(|v| format!("-D{v}")))
        .arg("-I".to_string() + &glsl.display().to_string())
        .args(includes.iter().map(|i| "-I".to_string() + &i.display().to_string()))
        .arg("-o")
        .arg(&spv)
        .arg(src)
        .output()
        .map_err(|e| {
            format!(
                "{}: cannot run {compiler} ({e}); install it with `apt-get install glslang-tools` or set GLSLANG_VALIDATOR",
                src.display()
            )
        })?;
    if output.status.success() {
        return Ok((name, spv));
    }
    let text = String::from_utf8_lossy(&output.stdout).to_string() + &String::from_utf8_lossy(&output.stderr);
    // glslangValidator prints "ERROR: /abs/path/file.frag:12: 'x' : undeclared identifier".
    let mut diags: Vec<String> = text
        .lines()
        .filter_map(|l| l.strip_prefix("ERROR: ").or_else(|| l.strip_prefix("WARNING: ")))
        .filter(|l| l.contains(':') && !l.starts_with(|c: char| c.is_ascii_digit()))
        .map(|l| {
            let l = l.trim();
            l.strip_prefix(&format!("{}/", glsl.parent().unwrap().display())).unwrap_or(l).to_string()
        })
        .collect();
    if diags.is_empty() {
        diags.push(format!("glsl/{name}: {}", text.trim()));
    }
    Err(diags.join("\n"))
}
