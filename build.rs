//! Compiles every shader under `glsl/` (not `glsl/common/`, which holds included headers)
//! to SPIR-V with the system `glslangValidator` and embeds the modules in the crate.
//!
//! Why the system compiler rather than the `glslang` crate: it comes from Debian's
//! `glslang-tools` in seconds, while the crate builds glslang from C++ source for ~95 s
//! per profile; CI pays that on every fresh clone. Shaders compile in parallel threads.

#[path = "build/layout.rs"]
#[allow(dead_code)]
mod layout;
#[path = "build/shaderc.rs"]
#[allow(dead_code)]
mod shaderc;

use std::fmt::Write as _;
use std::path::PathBuf;

use shaderc::{collect, compile_variant, variants};

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap());
    let glsl = root.join("glsl");
    let out = PathBuf::from(std::env::var("OUT_DIR").unwrap());
    // A directory makes cargo rerun when any file below it changes (or is added).
    println!("cargo:rerun-if-changed=glsl");
    println!("cargo:rerun-if-changed=build/shaderc.rs");
    println!("cargo:rerun-if-changed=build/layout.rs");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-env-changed=GLSLANG_VALIDATOR");

    // The shared declaration: the frame's and each family's file, concatenated; its Rust side
    // (`$OUT_DIR/layout.rs`, included by src/frame/layout.rs) and its GLSL side
    // (`#include "generated/layout.glsl"`), after checking that std430 and repr(C) agree on
    // every field's offset and that no two owners' push flags collide.
    let generated = out.join("glsl");
    let declared = layout_files(&root).and_then(|files| {
        for f in &files {
            println!("cargo:rerun-if-changed={f}");
        }
        let l = layout::merged()?;
        Ok((layout::glsl(&l)?, layout::rust(&l)))
    });
    match declared {
        Ok((glsl, rust)) => {
            std::fs::create_dir_all(generated.join("generated")).unwrap();
            write_if_changed(&generated.join("generated/layout.glsl"), &glsl);
            write_if_changed(&out.join("layout.rs"), &rust);
        }
        Err(e) => {
            for line in e.lines() {
                println!("cargo:warning={line}");
            }
            eprintln!("{e}");
            eprintln!("src/frame/layout.in.rs, src/methods/*/layout.in.rs: the shared layout is refused");
            std::process::exit(1);
        }
    }

    let mut sources = Vec::new();
    collect(&glsl, &mut sources);
    sources.sort();

    let compiler = std::env::var("GLSLANG_VALIDATOR").unwrap_or_else(|_| "glslangValidator".into());
    let results: Vec<Result<(String, PathBuf), String>> = std::thread::scope(|s| {
        // Each source, then each variant it declares.
        let jobs: Vec<(&PathBuf, Option<String>)> = sources
            .iter()
            .flat_map(|src| std::iter::once((src, None)).chain(variants(src).into_iter().map(move |v| (src, Some(v)))))
            .collect();
        let handles: Vec<_> = jobs
            .into_iter()
            .map(|(src, variant)| {
                let (glsl, out, compiler, generated) = (&glsl, &out, &compiler, &generated);
                s.spawn(move || compile_variant(compiler, glsl, &[generated], out, src, variant.as_deref()))
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

/// Rewritten only when it changes, so that its timestamp means something.
fn write_if_changed(path: &std::path::Path, text: &str) {
    if std::fs::read_to_string(path).ok().as_deref() != Some(text) {
        std::fs::write(path, text).unwrap();
    }
}

/// The declaration files: the frame's and every `src/methods/<family>/layout.in.rs`, which
/// must be the families build/layout.rs concatenates (it includes them at compile time).
fn layout_files(root: &std::path::Path) -> Result<Vec<String>, String> {
    let mut found: Vec<String> = std::fs::read_dir(root.join("src/methods"))
        .map_err(|e| format!("src/methods: {e}"))?
        .flatten()
        .filter(|e| e.path().join("layout.in.rs").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    found.sort();
    let mut listed: Vec<String> = layout::families().into_iter().map(String::from).collect();
    listed.sort();
    if found != listed {
        return Err(format!(
            "layout: src/methods/*/layout.in.rs are {found:?}, build/layout.rs concatenates {listed:?}: \
             add the family's line to its `declarations!`"
        ));
    }
    let mut files = vec!["src/frame/layout.in.rs".to_string()];
    files.extend(found.iter().map(|f| format!("src/methods/{f}/layout.in.rs")));
    Ok(files)
}
