//! The shared Rust/GLSL declaration (src/frame/layout.in.rs): the generator refuses fields
//! that std430 and repr(C) would place differently, the crate's structs sit where std430
//! puts them, and no shader declares by hand what the declaration generates.

#[path = "../build/layout.rs"]
#[allow(dead_code)]
#[macro_use]
mod layout;

use std::path::Path;

/// A declaration that is not the crate's: its own module, like `layout::declared`.
mod vec4_after_uint {
    gpu_structs! {
        struct Bad => struct Bad {
            count: uint,
            /// GLSL aligns it to 16, Rust's [f32; 4] to 4.
            position: vec4,
        }
    }
}

#[test]
fn vec4_after_a_single_uint_is_refused_naming_the_field() {
    let err = layout::check_structs(&vec4_after_uint::structs()).unwrap_err();
    println!("{err}");
    assert!(err.contains("struct `Bad`"), "{err}");
    assert!(err.contains("field `position`"), "{err}");
    assert!(err.contains("std430 places it at offset 16"), "{err}");
    assert!(err.contains("repr(C) at offset 4"), "{err}");
}

mod tail_padding {
    gpu_structs! {
        struct Tail => struct Tail {
            position: vec4,
            count: uint,
        }
    }
}

#[test]
fn struct_whose_std430_stride_exceeds_its_rust_size_is_refused() {
    let err = layout::check_structs(&tail_padding::structs()).unwrap_err();
    assert!(err.contains("struct `Tail`: std430 size 32"), "{err}");
    assert!(err.contains("repr(C) size 20"), "{err}");
}

mod nested {
    gpu_structs! {
        struct Inner => struct Inner { a: uint, b: uint }
        struct Outer => struct Outer { x: uint, inner: Inner, y: uint, v: vec4, pad: [uint; 2], n: [uint; 2] }
    }
}

#[test]
fn nested_structs_and_arrays_follow_std430() {
    let l = layout::check_structs(&nested::structs()).unwrap();
    // std430: a struct of uints aligns to 4, arrays of uints have stride 4.
    assert_eq!(l[1].fields, vec![("x", 0), ("inner", 4), ("y", 12), ("v", 16), ("pad", 32), ("n", 40)]);
    assert_eq!((l[1].size, l[1].align), (48, 16));
}

mod vec4_after_nested {
    gpu_structs! {
        struct Inner => struct Inner { a: uint, b: uint }
        struct Outer => struct Outer { x: uint, inner: Inner, v: vec4 }
    }
}

#[test]
fn vec4_after_a_nested_struct_of_uints_is_refused() {
    let err = layout::check_structs(&vec4_after_nested::structs()).unwrap_err();
    assert!(err.contains("struct `Outer` field `v`: std430 places it at offset 16"), "{err}");
    assert!(err.contains("repr(C) at offset 12"), "{err}");
}

#[test]
fn every_shared_struct_sits_where_std430_puts_it() {
    let generated = layout::check_structs(&layout::declared::structs()).expect("the declaration is consistent");
    let rust = specula::frame::layout::RUST_LAYOUTS;
    assert_eq!(generated.len(), rust.len());
    for (g, &(name, size, fields)) in generated.iter().zip(rust) {
        assert_eq!(g.rust, name);
        assert_eq!(g.size, size, "size_of::<{name}>() vs its std430 size");
        assert_eq!(g.fields, fields.to_vec(), "offset_of! in {name} vs std430");
    }
    // And by hand, for the names other code uses.
    use specula::frame::layout::*;
    use std::mem::{offset_of, size_of};
    let by_name = |n: &str| generated.iter().find(|g| g.rust == n).unwrap().clone();
    let offset = |n: &str, f: &str| by_name(n).fields.iter().find(|x| x.0 == f).unwrap().1;
    assert_eq!(size_of::<GpuView>(), by_name("GpuView").size);
    assert_eq!(offset_of!(GpuView, dir), offset("GpuView", "dir"));
    assert_eq!(size_of::<GpuMaterial>(), by_name("GpuMaterial").size);
    assert_eq!(offset_of!(GpuMaterial, kind), offset("GpuMaterial", "kind"));
    assert_eq!(offset_of!(GpuMaterial, thin), offset("GpuMaterial", "thin"));
    assert_eq!(size_of::<GpuObject>(), by_name("GpuObject").size);
    assert_eq!(offset_of!(GpuObject, reference_point), offset("GpuObject", "reference_point"));
    assert_eq!(size_of::<GpuLight>(), by_name("GpuLight").size);
    assert_eq!(offset_of!(GpuLight, shadow_view_proj), offset("GpuLight", "shadow_view_proj"));
    assert_eq!(size_of::<Push>(), by_name("Push").size);
    assert_eq!(offset_of!(Push, words), offset("Push", "words"));
    assert_eq!(specula::frame::PUSH_BYTES as usize, by_name("Push").size);
}

#[test]
fn bindings_come_from_the_declaration() {
    use specula::frame::layout::{binding, BINDINGS, MAP_BINDINGS};
    let sets = layout::declared::sets();
    for (set, rust) in sets.iter().zip([BINDINGS, MAP_BINDINGS]) {
        let declared: Vec<(u32, String)> = set.bindings.iter().map(|b| (b.binding, b.ty.to_string())).collect();
        assert!(rust.iter().all(|&(_, _, count)| count == 1));
        let rust: Vec<(u32, String)> = rust.iter().map(|&(b, ty, _)| (b, format!("{ty:?}"))).collect();
        assert_eq!(declared, rust, "{}", set.name);
    }
    assert_eq!(binding::THICKNESS, 3);
    let text = layout::glsl(&layout::declared()).unwrap();
    assert!(text.contains("layout(std430, set = 1, binding = 3) readonly buffer Thickness { float thickness[]; };"), "{text}");
    assert!(text.contains("layout(push_constant) uniform Push {"), "{text}");
    assert!(text.contains("    uint words[14];\n"), "{text}");
    assert!(text.contains("float push_search_tolerance() { return uintBitsToFloat(push.words[6]); }"), "{text}");
    assert!(text.contains("uint push_recursion_depth() { return push.words[0]; }"), "{text}");
    assert!(text.contains("    uint pad[2];\n"), "{text}");
    assert!(text.contains("const uint FLAG_FIRST_CYCLE = 16u;"), "{text}");
}

mod bad_sets {
    descriptor_sets! {
        A = set 0 {
            X = 0: STORAGE_BUFFER => "uniform sampler2D x";
            Y = 0: COMBINED_IMAGE_SAMPLER => "uniform sampler2D y";
        }
        B = set 2 {}
    }
}

#[test]
fn inconsistent_bindings_are_refused() {
    let err = layout::check_sets(&bad_sets::sets()).unwrap_err();
    assert!(err.contains("`A` binding `X`: `uniform sampler2D x` does not declare a STORAGE_BUFFER"), "{err}");
    assert!(err.contains("`A` declares binding 0 twice (`Y`)"), "{err}");
    assert!(err.contains("`B` is set 2, expected set 1"), "{err}");
}

/// Every `src/methods/<family>/layout.in.rs` is one that build/layout.rs concatenates (it
/// includes them at compile time, so a file it does not list would be silently left out).
#[test]
fn every_family_declaration_is_concatenated() {
    let methods = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/methods");
    let mut found: Vec<String> = std::fs::read_dir(&methods)
        .unwrap()
        .flatten()
        .filter(|e| e.path().join("layout.in.rs").is_file())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    found.sort();
    let mut listed: Vec<String> = layout::families().into_iter().map(String::from).collect();
    listed.sort();
    assert_eq!(found, listed);
    // Each family's part reaches both sides: a binding it adds to the frame's set, a struct.
    use specula::frame::layout::{binding, GpuRayQuery, BINDINGS};
    assert!(BINDINGS.iter().any(|&(b, _, _)| b == binding::CAUSTIC_FACES));
    let text = layout::glsl(&layout::declared()).unwrap();
    assert!(text.contains("layout(set = 0, binding = 8) uniform samplerCubeArray envmaps;"), "{text}");
    assert!(text.contains("struct RayQuery {"), "{text}");
    assert_eq!(std::mem::size_of::<GpuRayQuery>(), 48);
}

/// The declared push flags: no owner's bits alias a frame-wide flag, and each flag lies in the
/// range its owner declares.
#[test]
fn declared_push_flags_do_not_collide() {
    let l = layout::merged().unwrap_or_else(|e| panic!("{e}"));
    let every: Vec<_> = l.flags.iter().filter(|r| r.scope == "every_pass").collect();
    assert!(every.iter().any(|r| r.owner == "frame") && every.iter().any(|r| r.owner == "layered"));
    for r in &l.flags {
        assert!(r.bits.1 <= 32, "{} {:?}", r.owner, r.bits);
        for e in &every {
            let overlap = r.bits.0 < e.bits.1 && e.bits.0 < r.bits.1;
            assert!(std::ptr::eq(r, *e) || !overlap, "{} {:?} and {} {:?}", r.owner, r.bits, e.owner, e.bits);
        }
    }
}

mod frame_flags {
    gpu_consts! {
        FLAG_A: uint = 4096;
        FLAG_C: uint = 3;
        FLAG_LOOSE: uint = 1;
    }
    flag_bits! {
        every_pass 12..13 { FLAG_A }
        every_pass 0..2 { FLAG_C }
    }
}

mod family_flags {
    gpu_consts! {
        B_SHIFT: uint = 8;
        D_SHIFT: uint = 14;
    }
    flag_bits! {
        own_passes 8..16 { B_SHIFT: 8, D_SHIFT: 4, FLAG_A }
        own_passes 30..33 {}
    }
}

#[test]
fn colliding_push_flags_are_refused() {
    let owned = |mut f: Vec<layout::FlagBits>, owner| {
        f.iter_mut().for_each(|r| r.owner = owner);
        f
    };
    let l = layout::Layout {
        consts: frame_flags::consts().into_iter().chain(family_flags::consts()).collect(),
        flags: owned(frame_flags::flag_bits(), "frame").into_iter().chain(owned(family_flags::flag_bits(), "caustics")).collect(),
        ..Default::default()
    };
    let owners = vec![("frame", vec!["FLAG_A", "FLAG_C", "FLAG_LOOSE"]), ("caustics", vec!["B_SHIFT", "D_SHIFT"])];
    let err = layout::check_flags(&l, &owners).unwrap_err();
    println!("{err}");
    assert!(err.contains("caustics flag bits 8..16 (own_passes) overlap frame's bits 12..13 (every_pass)"), "{err}");
    assert!(err.contains("caustics flag bits 8..16: `D_SHIFT` takes bits 14..18, outside its range"), "{err}");
    assert!(err.contains("caustics flag bits 8..16: `FLAG_A` is not a uint const declared beside it"), "{err}");
    assert!(err.contains("frame flag bits 0..2: `FLAG_C` = 3 is not a single bit"), "{err}");
    assert!(err.contains("caustics flag bits 30..33: not a range of bits 0..32"), "{err}");
    assert!(err.contains("`FLAG_LOOSE` is in no declared flag range"), "{err}");
}

mod push_block {
    gpu_structs! {
        struct Push => push_constant Push push {
            view: uint,
            words: [uint; 4],
        }
    }
    gpu_consts! {
        TAKEN: uint = 1;
    }
    push_words! {
        0..2 { A: uint, B: float }
        1..3 { C: uint, TAKEN: uint }
        3..5 { D: vec4 }
    }
}

#[test]
fn colliding_push_words_are_refused() {
    let l = layout::Layout {
        structs: push_block::structs(),
        consts: push_block::consts(),
        words: push_block::push_words().into_iter().map(|w| layout::PushWords { owner: "layered", ..w }).collect(),
        ..Default::default()
    };
    let err = layout::check_words(&l).unwrap_err();
    println!("{err}");
    assert!(err.contains("layered push words 1..3 overlap layered's words 0..2"), "{err}");
    assert!(err.contains("`TAKEN` is declared twice"), "{err}");
    assert!(err.contains("push words 3..5: not a range of the push block's 4 words"), "{err}");
    assert!(err.contains("push words 3..5: 1 members for 2 words"), "{err}");
    assert!(err.contains("`D` is a vec4, not a uint or float"), "{err}");
    // The crate's own words pass, and fill the block.
    let own = layout::declared();
    layout::check_words(&own).unwrap();
    assert!(!own.words.is_empty());
}

fn sources(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).unwrap().flatten() {
        let p = e.path();
        if p.is_dir() {
            sources(&p, out);
        } else {
            out.push(p);
        }
    }
}

/// The shared structs, the push constants and the descriptor bindings of the scene shaders
/// come from generated/layout.glsl only. glsl/test/ holds stand-alone compute kernels for the
/// conformance tests, with their own bindings and push constants (none includes scene.glsl);
/// the one stand-alone pass, layered/count.vert (it runs before the frame's view table
/// exists), includes nothing and declares only its own push constant.
#[test]
fn no_shader_declares_the_shared_layout_by_hand() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("glsl");
    let mut files = Vec::new();
    sources(&root, &mut files);
    assert!(files.len() > 10, "{files:?}");
    let mut found = Vec::new();
    for f in &files {
        let text = std::fs::read_to_string(f).unwrap();
        let name = f.strip_prefix(&root).unwrap().to_string_lossy().replace('\\', "/");
        let standalone = name == "layered/count.vert" && !text.contains("#include") && !text.contains("binding");
        let kernel = name.starts_with("test/") || standalone;
        if kernel {
            assert!(!text.contains("common/scene.glsl"), "{name}: a test kernel includes the scene layout");
        }
        for (i, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap();
            let squeezed: String = code.split_whitespace().collect::<Vec<_>>().join(" ");
            for s in ["View", "Material", "Object", "Light"] {
                if squeezed.contains(&format!("struct {s} ")) || squeezed.ends_with(&format!("struct {s}")) {
                    found.push(format!("glsl/{name}:{}: declares struct {s}", i + 1));
                }
            }
            if !kernel && code.contains("push_constant") {
                found.push(format!("glsl/{name}:{}: declares a push_constant block", i + 1));
            }
            if !kernel && code.contains("binding") && code.contains("layout") {
                found.push(format!("glsl/{name}:{}: declares a descriptor binding", i + 1));
            }
        }
    }
    assert!(found.is_empty(), "declared in src/frame/layout.in.rs, not by hand:\n{}", found.join("\n"));
}
