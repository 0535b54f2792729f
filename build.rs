//! Compiles every shader under `glsl/` (not `glsl/common/`, which holds included headers)
//! to SPIR-V with the system `glslangValidator` and embeds the modules in the crate.
//!
//! Why the system compiler rather than the `glslang` crate: it comes from Debian's
//! `glslang-tools` in seconds, while the crate builds glslang from C++ source for ~95 s
//! per profile; CI pays that on every fresh clone. Shaders compile in parallel threads.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

const STAGES: &[&str] = &["vert", "frag", "comp", "geom", "tesc", "tese"];

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let glsl = root.join("glsl");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    // A directory makes cargo rerun when any file below it changes (or is added).
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-env-changed=GLSLANG_VALIDATOR");

    let mut sources = Vec::new();
    collect(&glsl, &mut sources);
    sources.sort();

    let compiler = std::env::var("GLSLANG_VALIDATOR").unwrap_or_else(|_| "glslangValidator".into());
    let results: Vec<Result<(String, PathBuf), String>> = std::thread::scope(|s| {
        let handles: Vec<_> = sources
            .iter()
            .map(|src| {
                let (glsl, out, compiler) = (&glsl, &out, &compiler);
                s.spawn(move || compile(compiler, glsl, out, src))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });

    let mut errors = Vec::new();
    let mut table = String::from(
        "/// Every embedded SPIR-V module: (name, bytes). Names are paths under `glsl/`.\npub static ALL: &[(&str, &[u8])] = &[\n",
    );
    for r in results {
        match r {
            Ok((name, spv)) => writeln!(table, "    ({name:?}, include_bytes!({:?})),", spv.display().to_string()).unwrap(),
            Err(e) => errors.push(e),
        }
    }
    table.push_str("];\n");
    if !errors.is_empty() {
        for e in &errors {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
        }
        eprintln!("{}", errors.join("\n"));
        eprintln!("shader compilation failed ({} shader(s))", errors.len());
        std::process::exit(1);
    }
    std::fs::write(out.join("shaders.rs"), table).unwrap();
}

fn collect(dir: &Path, out: &mut Vec<PathBuf>) {
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
fn compile(compiler: &str, glsl: &Path, out: &Path, src: &Path) -> Result<(String, PathBuf), String> {
    let name = src.strip_prefix(glsl).unwrap().to_string_lossy().replace('\\', "/");
    let spv = out.join(format!("{}.spv", name.replace('/', "__")));
    let output = Command::new(compiler)
        .args(["-V", "--target-env", "vulkan1.3", "-Os"])
        .arg("-I".to_string() + &glsl.display().to_string())
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
