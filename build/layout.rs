//! What Rust and GLSL share, read from its declarations for build.rs (which writes
//! `$OUT_DIR/glsl/generated/layout.glsl` and `$OUT_DIR/layout.rs`) and for tests/layout.rs.
//!
//! The frame declares its own part in src/frame/layout.in.rs; each method family that shares
//! anything with its shaders declares its part in src/methods/<family>/layout.in.rs (listed in
//! [`FAMILIES`]). Each file is a few macro invocations, which expand here into a description
//! ([`Layout`]); [`declared`] concatenates them (a family may add bindings to a set the frame
//! declares), and [`glsl`] and [`rust`] write the two twins, after [`check_structs`] has laid
//! every struct out twice, as std430 and as `repr(C)` of the Rust type each field maps to, and
//! refused any field that the two place differently, and [`check_flags`] has refused push
//! flags outside the bits their owner declares.

use std::fmt::Write as _;

/// A field's type, as the declaration spells it (GLSL names; structs by their Rust name).
#[derive(Clone, Debug, PartialEq)]
pub enum Ty {
    Float,
    Int,
    Uint,
    Vec3,
    Vec4,
    UVec4,
    Mat4,
    Array(Box<Ty>, usize),
    /// A struct declared earlier, by its Rust name.
    Struct(&'static str),
}

pub struct Field {
    pub name: &'static str,
    pub ty: Ty,
    pub doc: Vec<&'static str>,
}

pub struct StructDecl {
    pub rust: &'static str,
    /// `struct` (a GLSL struct) or `push_constant` (the push-constant block).
    pub kind: &'static str,
    pub glsl: &'static str,
    /// The block's instance name (`push_constant` only).
    pub instance: &'static str,
    pub doc: Vec<&'static str>,
    pub fields: Vec<Field>,
}

pub struct ConstDecl {
    pub name: &'static str,
    pub ty: Ty,
    pub value: &'static str,
    pub doc: Vec<&'static str>,
}

pub struct BindingDecl {
    pub name: &'static str,
    pub binding: u32,
    /// `vk::DescriptorType` variant, e.g. `STORAGE_BUFFER`.
    pub ty: &'static str,
    /// The GLSL declaration after its `layout(…)`, without the `;`.
    pub decl: &'static str,
    pub doc: Vec<&'static str>,
}

pub struct SetDecl {
    /// The Rust const holding the set's bindings, e.g. `BINDINGS`.
    pub name: &'static str,
    pub set: u32,
    pub doc: Vec<&'static str>,
    pub bindings: Vec<BindingDecl>,
}

/// A range of `Push.flags` bits that one owner (the frame or a family) declares, with the
/// consts that live in it: single-bit flags, and fields (a `_SHIFT` const and its width).
pub struct FlagBits {
    /// `frame` or the family's folder name (filled in by [`declared`]).
    pub owner: &'static str,
    /// `every_pass`: set in the frame-wide flags, so any pass may see them; `own_passes`: set
    /// only on the owner's own passes (no pass belongs to two families, so owners may reuse
    /// each other's `own_passes` bits, never an `every_pass` bit).
    pub scope: &'static str,
    /// [start, end)
    pub bits: (u32, u32),
    /// (const, width): width 0 for a single-bit flag (its value is the bit), else the const is
    /// a shift and the field takes `width` bits from it.
    pub members: Vec<(&'static str, u32)>,
    pub doc: Vec<&'static str>,
}

/// Words of the push block's `words` array that one owner (the frame or a family) declares:
/// set once a frame for every pass (by the frame, and by each family's `push_words` hook),
/// read by the owner's shaders and by shaders of families that share the owner's facility (the
/// distance-map search of `common/search.glsl`). The frame-wide block itself holds only what
/// every pass reads (view, object, flags, lights).
pub struct PushWords {
    /// `frame` or the family's folder name (filled in by [`declared`]).
    pub owner: &'static str,
    /// [start, end): the members take these words in order.
    pub words: (u32, u32),
    /// (name, `uint` or `float`, doc)
    pub members: Vec<(&'static str, Ty, Vec<&'static str>)>,
    pub doc: Vec<&'static str>,
}

#[derive(Default)]
pub struct Layout {
    pub structs: Vec<StructDecl>,
    pub consts: Vec<ConstDecl>,
    pub sets: Vec<SetDecl>,
    pub flags: Vec<FlagBits>,
    pub words: Vec<PushWords>,
}

/// One struct laid out both ways (they agree, or `check_structs` failed).
#[derive(Clone, Debug, PartialEq)]
pub struct StructLayout {
    pub rust: &'static str,
    pub glsl: &'static str,
    /// std430 size (array stride of the struct; end of the block for push constants).
    pub size: usize,
    pub align: usize,
    /// `size_of` / `align_of` of the Rust struct.
    pub rust_size: usize,
    pub rust_align: usize,
    /// (field, offset), the same in std430 and `repr(C)`.
    pub fields: Vec<(&'static str, usize)>,
}

fn round_up(x: usize, a: usize) -> usize {
    x.div_ceil(a) * a
}

impl Ty {
    pub fn glsl_name(&self, structs: &[StructDecl]) -> String {
        match self {
            Ty::Float => "float".into(),
            Ty::Int => "int".into(),
            Ty::Uint => "uint".into(),
            Ty::Vec3 => "vec3".into(),
            Ty::Vec4 => "vec4".into(),
            Ty::UVec4 => "uvec4".into(),
            Ty::Mat4 => "mat4".into(),
            Ty::Array(t, _) => t.glsl_name(structs),
            Ty::Struct(s) => structs.iter().find(|d| d.rust == *s).map_or(*s, |d| d.glsl).into(),
        }
    }

    /// The Rust type the field maps to (what src/frame/layout.rs declares).
    pub fn rust_name(&self) -> String {
        match self {
            Ty::Float => "f32".into(),
            Ty::Int => "i32".into(),
            Ty::Uint => "u32".into(),
            Ty::Vec3 => "[f32; 3]".into(),
            Ty::Vec4 => "[f32; 4]".into(),
            Ty::UVec4 => "[u32; 4]".into(),
            Ty::Mat4 => "[[f32; 4]; 4]".into(),
            Ty::Array(t, n) => format!("[{}; {n}]", t.rust_name()),
            Ty::Struct(s) => (*s).into(),
        }
    }

    /// std430 (size, base alignment).
    pub fn std430(&self, done: &[StructLayout]) -> Result<(usize, usize), String> {
        Ok(match self {
            Ty::Float | Ty::Int | Ty::Uint => (4, 4),
            Ty::Vec3 => (12, 16),
            Ty::Vec4 | Ty::UVec4 => (16, 16),
            // Column-major: an array of four vec4 columns.
            Ty::Mat4 => (64, 16),
            // std430: the stride is the element's size rounded up to its alignment (no
            // rounding to 16 as in std140).
            Ty::Array(t, n) => {
                let (s, a) = t.std430(done)?;
                (round_up(s, a) * n, a)
            }
            // std430: a struct aligns as its most aligned member; its size is rounded up to that.
            Ty::Struct(s) => {
                let l = find(done, s)?;
                (l.size, l.align)
            }
        })
    }

    /// `repr(C)` (size, alignment) of the Rust type: every float and integer aligns to 4,
    /// so `[f32; 4]` aligns to 4 where GLSL's vec4 aligns to 16.
    pub fn repr_c(&self, done: &[StructLayout]) -> Result<(usize, usize), String> {
        Ok(match self {
            Ty::Float | Ty::Int | Ty::Uint => (4, 4),
            Ty::Vec3 => (12, 4),
            Ty::Vec4 | Ty::UVec4 => (16, 4),
            Ty::Mat4 => (64, 4),
            Ty::Array(t, n) => {
                let (s, a) = t.repr_c(done)?;
                (s * n, a)
            }
            Ty::Struct(s) => {
                let l = find(done, s)?;
                (l.rust_size, l.rust_align)
            }
        })
    }
}

fn find<'a>(done: &'a [StructLayout], name: &str) -> Result<&'a StructLayout, String> {
    done.iter().find(|l| l.rust == name).ok_or_else(|| format!("`{name}` is not a struct declared before it"))
}

/// Lays out every struct as std430 and as `repr(C)`; refuses (naming struct and field) any
/// field the two place at different offsets, and any struct whose sizes differ.
pub fn check_structs(structs: &[StructDecl]) -> Result<Vec<StructLayout>, String> {
    let mut done: Vec<StructLayout> = Vec::new();
    let mut errors = Vec::new();
    for s in structs {
        let name = if s.rust == s.glsl { format!("`{}`", s.rust) } else { format!("`{}` (GLSL `{}`)", s.rust, s.glsl) };
        match (s.kind, s.instance) {
            ("struct", "") => {}
            ("push_constant", i) if !i.is_empty() => {}
            ("push_constant", _) => errors.push(format!("layout: push-constant block {name} needs an instance name")),
            (k, _) => errors.push(format!("layout: {name}: unknown kind `{k}` (struct or push_constant)")),
        }
        let (mut end430, mut align430, mut end_c, mut align_c) = (0, 4, 0, 1);
        let mut fields = Vec::new();
        let mut ok = true;
        for f in &s.fields {
            if fields.iter().any(|(n, _)| *n == f.name) {
                errors.push(format!("layout: struct {name} declares field `{}` twice", f.name));
                ok = false;
                break;
            }
            if let Ty::Struct(n) = &f.ty {
                if structs.iter().any(|d| d.rust == *n && d.kind != "struct") {
                    errors.push(format!("layout: struct {name} field `{}`: `{n}` is not a struct", f.name));
                    ok = false;
                    break;
                }
            }
            let sizes = f.ty.std430(&done).and_then(|g| Ok((g, f.ty.repr_c(&done)?)));
            let ((size430, a430), (size_c, a_c)) = match sizes {
                Ok(x) => x,
                Err(e) => {
                    errors.push(format!("layout: struct {name} field `{}`: {e}", f.name));
                    ok = false;
                    break;
                }
            };
            let (o430, o_c) = (round_up(end430, a430), round_up(end_c, a_c));
            if o430 != o_c {
                errors.push(format!(
                    "layout: struct {name} field `{}`: std430 places it at offset {o430} ({} aligns to {a430}), \
                     repr(C) at offset {o_c} ({} aligns to {a_c}); GLSL would pad where Rust does not: \
                     move the field or declare the padding explicitly",
                    f.name,
                    f.ty.glsl_name(structs),
                    f.ty.rust_name()
                ));
                ok = false;
                break;
            }
            fields.push((f.name, o430));
            (end430, align430) = (o430 + size430, align430.max(a430));
            (end_c, align_c) = (o_c + size_c, align_c.max(a_c));
        }
        if !ok {
            continue;
        }
        // A struct is an array element (its std430 size is its stride); a block is not.
        let size = if s.kind == "struct" { round_up(end430, align430) } else { end430 };
        let rust_size = round_up(end_c, align_c);
        if size != rust_size {
            errors.push(format!(
                "layout: struct {name}: std430 size {size} (aligned to {align430}), repr(C) size {rust_size}; \
                 pad the end explicitly so that both agree"
            ));
            continue;
        }
        done.push(StructLayout { rust: s.rust, glsl: s.glsl, size, align: align430, rust_size, rust_align: align_c, fields });
    }
    if structs.iter().filter(|s| s.kind == "push_constant").count() > 1 {
        errors.push("layout: more than one push-constant block".into());
    }
    if errors.is_empty() {
        Ok(done)
    } else {
        Err(errors.join("\n"))
    }
}

/// Refuses descriptor sets that are not numbered 0, 1, … in order, repeated bindings, and
/// declarations that do not match their descriptor type.
pub fn check_sets(sets: &[SetDecl]) -> Result<(), String> {
    let mut errors = Vec::new();
    for (i, s) in sets.iter().enumerate() {
        if s.set as usize != i {
            errors.push(format!("layout: `{}` is set {}, expected set {i} (sets are declared in order)", s.name, s.set));
        }
        for (j, b) in s.bindings.iter().enumerate() {
            if s.bindings[..j].iter().any(|o| o.binding == b.binding) {
                errors.push(format!("layout: `{}` declares binding {} twice (`{}`)", s.name, b.binding, b.name));
            }
            let fits = match b.ty {
                "STORAGE_BUFFER" => b.decl.contains("buffer "),
                "UNIFORM_BUFFER" => b.decl.starts_with("uniform ") && !b.decl.contains("sampler"),
                "COMBINED_IMAGE_SAMPLER" => b.decl.starts_with("uniform sampler"),
                "STORAGE_IMAGE" => b.decl.contains("image"),
                "ACCELERATION_STRUCTURE_KHR" => b.decl.starts_with("uniform accelerationStructureEXT"),
                _ => false,
            };
            if !fits {
                errors.push(format!("layout: `{}` binding `{}`: `{}` does not declare a {}", s.name, b.name, b.decl, b.ty));
            }
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("\n"))
    }
}

fn comment(out: &mut String, indent: &str, doc: &[&str]) {
    for d in doc {
        for line in d.lines() {
            let line = line.strip_prefix(' ').unwrap_or(line);
            if line.is_empty() {
                writeln!(out, "{indent}//").unwrap();
            } else {
                writeln!(out, "{indent}// {line}").unwrap();
            }
        }
    }
}

/// The GLSL text of the declaration (after checking it): consts, structs, the bindings of
/// every set, the push-constant block.
pub fn glsl(l: &Layout) -> Result<String, String> {
    check_structs(&l.structs)?;
    check_sets(&l.sets)?;
    let mut out = String::from(
        "// Generated by build.rs (build/layout.rs) from src/frame/layout.in.rs and\n\
         // src/methods/*/layout.in.rs, which also give the Rust side its structs and consts.\n\
         // Do not edit: change the declarations.\n\
         #ifndef SPECULA_GENERATED_LAYOUT_GLSL\n#define SPECULA_GENERATED_LAYOUT_GLSL\n",
    );
    for (i, c) in l.consts.iter().enumerate() {
        // A documented const starts a group.
        if i == 0 || !c.doc.is_empty() {
            out.push('\n');
        }
        comment(&mut out, "", &c.doc);
        let ty = c.ty.glsl_name(&l.structs);
        let suffix = if c.ty == Ty::Uint { "u" } else { "" };
        writeln!(out, "const {ty} {} = {}{suffix};", c.name, c.value).unwrap();
    }
    let field = |out: &mut String, f: &Field| {
        comment(out, "    ", &f.doc);
        let n = match &f.ty {
            Ty::Array(_, n) => format!("[{n}]"),
            _ => String::new(),
        };
        writeln!(out, "    {} {}{n};", f.ty.glsl_name(&l.structs), f.name).unwrap();
    };
    for s in l.structs.iter().filter(|s| s.kind == "struct") {
        out.push('\n');
        comment(&mut out, "", &s.doc);
        writeln!(out, "struct {} {{", s.glsl).unwrap();
        s.fields.iter().for_each(|f| field(&mut out, f));
        out.push_str("};\n");
    }
    for set in &l.sets {
        out.push('\n');
        comment(&mut out, "", &set.doc);
        // A set that holds an acceleration structure needs GL_EXT_ray_query, which only the
        // shaders that trace through it enable (defining SPECULA_RAY_QUERY before the include):
        // the whole set is declared there alone.
        let ray_query = set.bindings.iter().any(|b| b.ty == "ACCELERATION_STRUCTURE_KHR");
        if ray_query {
            out.push_str("#ifdef SPECULA_RAY_QUERY\n");
        }
        for b in &set.bindings {
            comment(&mut out, "", &b.doc);
            let std430 = if b.ty == "STORAGE_BUFFER" || b.ty == "UNIFORM_BUFFER" { "std430, " } else { "" };
            writeln!(out, "layout({std430}set = {}, binding = {}) {};", set.set, b.binding, b.decl).unwrap();
        }
        if ray_query {
            out.push_str("#endif\n");
        }
    }
    for s in l.structs.iter().filter(|s| s.kind == "push_constant") {
        out.push('\n');
        comment(&mut out, "", &s.doc);
        writeln!(out, "layout(push_constant) uniform {} {{", s.glsl).unwrap();
        s.fields.iter().for_each(|f| field(&mut out, f));
        writeln!(out, "}} {};", s.instance).unwrap();
        for r in &l.words {
            out.push('\n');
            comment(&mut out, "", &r.doc);
            for (k, (name, ty, doc)) in r.members.iter().enumerate() {
                comment(&mut out, "", doc);
                let w = format!("{}.words[{}]", s.instance, r.words.0 as usize + k);
                let (t, v) = if *ty == Ty::Float { ("float", format!("uintBitsToFloat({w})")) } else { ("uint", w) };
                writeln!(out, "{t} push_{}() {{ return {v}; }}", name.to_lowercase()).unwrap();
            }
        }
    }
    out.push_str("\n#endif\n");
    Ok(out)
}

/// A declared field type as [`Ty`].
#[macro_export]
macro_rules! layout_ty {
    (float) => {
        $crate::layout::Ty::Float
    };
    (int) => {
        $crate::layout::Ty::Int
    };
    (uint) => {
        $crate::layout::Ty::Uint
    };
    (vec3) => {
        $crate::layout::Ty::Vec3
    };
    (vec4) => {
        $crate::layout::Ty::Vec4
    };
    (uvec4) => {
        $crate::layout::Ty::UVec4
    };
    (mat4) => {
        $crate::layout::Ty::Mat4
    };
    ([$t:tt; $n:literal]) => {
        $crate::layout::Ty::Array(Box::new($crate::layout_ty!($t)), $n)
    };
    ($s:ident) => {
        $crate::layout::Ty::Struct(stringify!($s))
    };
}

/// The structs (and the push-constant block): `pub fn structs() -> Vec<StructDecl>`.
#[macro_export]
macro_rules! gpu_structs {
    ($(
        $(#[doc = $doc:literal])*
        struct $rust:ident => $kind:ident $glsl:ident $($instance:ident)? {
            $( $(#[doc = $fdoc:literal])* $field:ident : $ty:tt ),* $(,)?
        }
    )*) => {
        pub fn structs() -> Vec<$crate::layout::StructDecl> {
            vec![$($crate::layout::StructDecl {
                rust: stringify!($rust),
                kind: stringify!($kind),
                glsl: stringify!($glsl),
                instance: concat!($(stringify!($instance))?),
                doc: vec![$($doc),*],
                fields: vec![$($crate::layout::Field {
                    name: stringify!($field),
                    ty: $crate::layout_ty!($ty),
                    doc: vec![$($fdoc),*],
                }),*],
            }),*]
        }
    };
}

/// The consts: `pub fn consts() -> Vec<ConstDecl>`.
#[macro_export]
macro_rules! gpu_consts {
    ($( $(#[doc = $doc:literal])* $name:ident : $ty:tt = $value:literal; )*) => {
        pub fn consts() -> Vec<$crate::layout::ConstDecl> {
            vec![$($crate::layout::ConstDecl {
                name: stringify!($name),
                ty: $crate::layout_ty!($ty),
                value: stringify!($value),
                doc: vec![$($doc),*],
            }),*]
        }
    };
}

/// The descriptor sets: `pub fn sets() -> Vec<SetDecl>`.
#[macro_export]
macro_rules! descriptor_sets {
    ($(
        $(#[doc = $doc:literal])*
        $set_name:ident = set $set:literal {
            $( $(#[doc = $bdoc:literal])* $name:ident = $binding:literal : $ty:ident => $decl:literal; )*
        }
    )*) => {
        pub fn sets() -> Vec<$crate::layout::SetDecl> {
            vec![$($crate::layout::SetDecl {
                name: stringify!($set_name),
                set: $set,
                doc: vec![$($doc),*],
                bindings: vec![$($crate::layout::BindingDecl {
                    name: stringify!($name),
                    binding: $binding,
                    ty: stringify!($ty),
                    decl: $decl,
                    doc: vec![$($bdoc),*],
                }),*],
            }),*]
        }
    };
}

/// The push-flag bits: `pub fn flag_bits() -> Vec<FlagBits>` (the owner is filled in by
/// [`declared`]). `scope start..end { FLAG_A, FIELD_SHIFT: width, … }`.
#[macro_export]
macro_rules! flag_bits {
    ($(
        $(#[doc = $doc:literal])*
        $scope:ident $start:literal .. $end:literal { $( $name:ident $(: $width:literal)? ),* $(,)? }
    )*) => {
        pub fn flag_bits() -> Vec<$crate::layout::FlagBits> {
            vec![$($crate::layout::FlagBits {
                owner: "",
                scope: stringify!($scope),
                bits: ($start, $end),
                members: vec![$( (stringify!($name), 0 $(+ $width)?) ),*],
                doc: vec![$($doc),*],
            }),*]
        }
    };
}

/// The push words: `pub fn push_words() -> Vec<PushWords>` (the owner is filled in by
/// [`declared`]). `start..end { NAME: uint, NAME: float, … }`, one word each, in order.
#[macro_export]
macro_rules! push_words {
    ($(
        $(#[doc = $doc:literal])*
        $start:literal .. $end:literal { $( $(#[doc = $mdoc:literal])* $name:ident : $ty:tt ),* $(,)? }
    )*) => {
        pub fn push_words() -> Vec<$crate::layout::PushWords> {
            vec![$($crate::layout::PushWords {
                owner: "",
                words: ($start, $end),
                members: vec![$( (stringify!($name), $crate::layout_ty!($ty), vec![$($mdoc),*]) ),*],
                doc: vec![$($doc),*],
            }),*]
        }
    };
}

/// Refuses push-word declarations that can collide: a range outside the push block's `words`
/// array, two ranges that overlap (whoever owns them: every word is set on every pass), a
/// range whose members do not fill it exactly, a member that is neither `uint` nor `float`,
/// and a name declared twice (as a word or a const).
pub fn check_words(l: &Layout) -> Result<(), String> {
    let mut errors = Vec::new();
    let count = l.structs.iter().filter(|s| s.kind == "push_constant").flat_map(|s| s.fields.iter()).find_map(|f| match &f.ty {
        Ty::Array(t, n) if f.name == "words" && **t == Ty::Uint => Some(*n as u32),
        _ => None,
    });
    if !l.words.is_empty() && count.is_none() {
        errors.push("layout: push words are declared but the push block has no `words: [uint; N]`".into());
    }
    let count = count.unwrap_or(0);
    for (i, r) in l.words.iter().enumerate() {
        let (start, end) = r.words;
        let what = format!("layout: {} push words {start}..{end}", r.owner);
        if start >= end || end > count {
            errors.push(format!("{what}: not a range of the push block's {count} words"));
        }
        if r.members.len() as u32 != end.saturating_sub(start) {
            errors.push(format!("{what}: {} members for {} words", r.members.len(), end.saturating_sub(start)));
        }
        for o in &l.words[..i] {
            if start < o.words.1 && o.words.0 < end {
                errors.push(format!("{what} overlap {}'s words {}..{}", o.owner, o.words.0, o.words.1));
            }
        }
        for (name, ty, _) in &r.members {
            if *ty != Ty::Uint && *ty != Ty::Float {
                errors.push(format!("{what}: `{name}` is a {}, not a uint or float", ty.glsl_name(&l.structs)));
            }
            let twice = l.words.iter().flat_map(|o| o.members.iter()).filter(|m| m.0 == *name).count() > 1;
            if twice || l.consts.iter().any(|c| c.name == *name) {
                errors.push(format!("{what}: `{name}` is declared twice"));
            }
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("\n"))
    }
}

/// Refuses push-flag declarations that can collide: a range past bit 32 or of an unknown
/// scope; an `every_pass` range that overlaps any other owner's range (`own_passes` ranges of
/// different owners may overlap: no pass is two families'); a member that is not a uint const
/// of its owner, or whose bits leave its range; and a `FLAG_*` const in no range.
pub fn check_flags(l: &Layout, owners: &[(&'static str, Vec<&'static str>)]) -> Result<(), String> {
    let mut errors = Vec::new();
    let value = |name: &str| l.consts.iter().find(|c| c.name == name && c.ty == Ty::Uint).and_then(|c| c.value.parse::<u32>().ok());
    for (i, r) in l.flags.iter().enumerate() {
        let (start, end) = r.bits;
        let what = format!("layout: {} flag bits {start}..{end}", r.owner);
        if start >= end || end > 32 {
            errors.push(format!("{what}: not a range of bits 0..32"));
        }
        if r.scope != "every_pass" && r.scope != "own_passes" {
            errors.push(format!("{what}: unknown scope `{}` (every_pass or own_passes)", r.scope));
        }
        for o in &l.flags[..i] {
            let overlap = start < o.bits.1 && o.bits.0 < end;
            let shared = r.scope == "own_passes" && o.scope == "own_passes" && r.owner != o.owner;
            if overlap && !shared {
                errors.push(format!("{what} ({}) overlap {}'s bits {}..{} ({})", r.scope, o.owner, o.bits.0, o.bits.1, o.scope));
            }
        }
        let own = owners.iter().find(|(o, _)| *o == r.owner).map_or(&[][..], |(_, c)| &c[..]);
        for &(name, width) in &r.members {
            let Some(v) = value(name).filter(|_| own.contains(&name)) else {
                errors.push(format!("{what}: `{name}` is not a uint const declared beside it"));
                continue;
            };
            let (lo, hi) = if width == 0 {
                if !v.is_power_of_two() {
                    errors.push(format!("{what}: `{name}` = {v} is not a single bit (a field names its width)"));
                    continue;
                }
                (v.trailing_zeros(), v.trailing_zeros() + 1)
            } else {
                (v, v.saturating_add(width))
            };
            if lo < start || hi > end {
                errors.push(format!("{what}: `{name}` takes bits {lo}..{hi}, outside its range"));
            }
        }
    }
    for c in l.consts.iter().filter(|c| c.name.starts_with("FLAG_")) {
        if !l.flags.iter().any(|r| r.members.iter().any(|m| m.0 == c.name)) {
            errors.push(format!("layout: `{}` is in no declared flag range (flag_bits!)", c.name));
        }
    }
    if errors.is_empty() {
        Ok(())
    } else {
        Err(errors.join("\n"))
    }
}

/// The Rust text of the declaration (src/frame/layout.rs includes it): the `#[repr(C)]`
/// structs with `RUST_LAYOUTS` (tests/layout.rs compares it with [`check_structs`]), the
/// consts, each set's bindings and `binding::*`.
pub fn rust(l: &Layout) -> String {
    let mut out = String::from(
        "// Generated by build.rs (build/layout.rs) from src/frame/layout.in.rs and\n\
         // src/methods/*/layout.in.rs. Do not edit: change the declarations.\n",
    );
    let doc = |out: &mut String, indent: &str, doc: &[&str]| {
        doc.iter().for_each(|d| writeln!(out, "{indent}#[doc = {d:?}]").unwrap());
    };
    for s in &l.structs {
        out.push('\n');
        doc(&mut out, "", &s.doc);
        out.push_str("#[repr(C)]\n#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]\n");
        writeln!(out, "pub struct {} {{", s.rust).unwrap();
        for f in &s.fields {
            doc(&mut out, "    ", &f.doc);
            writeln!(out, "    pub {}: {},", f.name, f.ty.rust_name()).unwrap();
        }
        out.push_str("}\n");
    }
    out.push_str(
        "\n/// Every shared struct as Rust lays it out: (name, size, [(field, offset)]), for the\n\
         /// test that compares it with the generator's std430 offsets (tests/layout.rs).\n\
         #[doc(hidden)]\n#[allow(clippy::type_complexity)]\npub const RUST_LAYOUTS: &[(&str, usize, &[(&str, usize)])] = &[\n",
    );
    for s in &l.structs {
        let fields: Vec<String> =
            s.fields.iter().map(|f| format!("({:?}, std::mem::offset_of!({}, {}))", f.name, s.rust, f.name)).collect();
        writeln!(out, "    ({:?}, std::mem::size_of::<{}>(), &[{}]),", s.rust, s.rust, fields.join(", ")).unwrap();
    }
    out.push_str("];\n\n");
    for c in &l.consts {
        doc(&mut out, "", &c.doc);
        writeln!(out, "pub const {}: {} = {};", c.name, c.ty.rust_name(), c.value).unwrap();
    }
    for r in &l.words {
        out.push('\n');
        doc(&mut out, "", &r.doc);
        for (k, (name, ty, d)) in r.members.iter().enumerate() {
            doc(&mut out, "", d);
            let w = r.words.0 as usize + k;
            writeln!(out, "pub const {name}: crate::frame::words::Word<{}> = crate::frame::words::Word::at({w});", ty.rust_name()).unwrap();
        }
    }
    for set in &l.sets {
        out.push('\n');
        doc(&mut out, "", &set.doc);
        let bindings: Vec<String> = set.bindings.iter().map(|b| format!("({}, ash::vk::DescriptorType::{}, 1)", b.binding, b.ty)).collect();
        writeln!(out, "pub const {}: &[crate::vk::pipeline::Binding] = &[{}];", set.name, bindings.join(", ")).unwrap();
    }
    out.push_str("\n/// Binding numbers, by the name of what they bind.\npub mod binding {\n");
    for b in l.sets.iter().flat_map(|s| &s.bindings) {
        doc(&mut out, "    ", &b.doc);
        writeln!(out, "    #[doc = {:?}]\n    pub const {}: u32 = {};", format!("`{}`", b.decl), b.name, b.binding).unwrap();
    }
    out.push_str("}\n");
    out
}

/// What a declaration file leaves out is empty (its own functions shadow these).
pub mod empty {
    pub fn structs() -> Vec<super::StructDecl> {
        Vec::new()
    }
    pub fn consts() -> Vec<super::ConstDecl> {
        Vec::new()
    }
    pub fn sets() -> Vec<super::SetDecl> {
        Vec::new()
    }
    pub fn flag_bits() -> Vec<super::FlagBits> {
        Vec::new()
    }
    pub fn push_words() -> Vec<super::PushWords> {
        Vec::new()
    }
}

/// The declaration files, each as a module named after its owner: the frame's, then each
/// family's folder that has one, in the order they are concatenated. A family that adds a
/// `layout.in.rs` adds its line here (build.rs and tests/layout.rs refuse a file missing here).
macro_rules! declarations {
    ($($owner:ident => $path:literal,)*) => {
        pub mod declared {
            $(
                #[allow(unused_imports)]
                pub mod $owner {
                    pub use super::super::empty::*;
                    include!($path);
                }
            )*

            /// (owner, its declaration) in order.
            pub fn files() -> Vec<(&'static str, super::Layout)> {
                vec![$((stringify!($owner), super::Layout {
                    structs: $owner::structs(),
                    consts: $owner::consts(),
                    sets: $owner::sets(),
                    flags: $owner::flag_bits(),
                    words: $owner::push_words(),
                })),*]
            }

            pub fn structs() -> Vec<super::StructDecl> {
                super::declared().structs
            }
            pub fn consts() -> Vec<super::ConstDecl> {
                super::declared().consts
            }
            pub fn sets() -> Vec<super::SetDecl> {
                super::declared().sets
            }
        }
    };
}

declarations! {
    frame => "../src/frame/layout.in.rs",
    envmap => "../src/methods/envmap/layout.in.rs",
    distance => "../src/methods/distance/layout.in.rs",
    layered => "../src/methods/layered/layout.in.rs",
    geometry => "../src/methods/geometry/layout.in.rs",
    raytrace => "../src/methods/raytrace/layout.in.rs",
    caustics => "../src/methods/caustics/layout.in.rs",
}

/// The families with a declaration file (`src/methods/<family>/layout.in.rs`).
pub fn families() -> Vec<&'static str> {
    declared::files().into_iter().map(|(o, _)| o).filter(|&o| o != "frame").collect()
}

/// The declaration files concatenated in order: structs, consts and flag ranges one after the
/// other; a set declared again (same name and number: a family adding bindings to one the
/// frame declares) takes the new bindings, the sets sorted by number and their bindings by
/// binding; and the flag ranges checked ([`check_flags`]).
pub fn merged() -> Result<Layout, String> {
    let mut l = Layout::default();
    let mut owners = Vec::new();
    let mut errors = Vec::new();
    for (owner, file) in declared::files() {
        owners.push((owner, file.consts.iter().map(|c| c.name).collect::<Vec<_>>()));
        l.structs.extend(file.structs);
        l.consts.extend(file.consts);
        l.flags.extend(file.flags.into_iter().map(|f| FlagBits { owner, ..f }));
        l.words.extend(file.words.into_iter().map(|w| PushWords { owner, ..w }));
        for mut set in file.sets {
            match l.sets.iter_mut().find(|s| s.set == set.set || s.name == set.name) {
                Some(s) if s.set == set.set && s.name == set.name => {
                    // The continuation's doc says what its bindings are.
                    if let Some(b) = set.bindings.first_mut() {
                        b.doc.splice(0..0, set.doc);
                    }
                    s.bindings.extend(set.bindings);
                }
                Some(s) => errors.push(format!(
                    "layout: {owner} declares `{}` = set {}, which the layout has as `{}` = set {}",
                    set.name, set.set, s.name, s.set
                )),
                None => l.sets.push(set),
            }
        }
    }
    l.sets.sort_by_key(|s| s.set);
    l.sets.iter_mut().for_each(|s| s.bindings.sort_by_key(|b| b.binding));
    for (i, c) in l.consts.iter().enumerate() {
        if l.consts[..i].iter().any(|o| o.name == c.name) {
            errors.push(format!("layout: const `{}` is declared twice", c.name));
        }
    }
    if let Err(e) = check_flags(&l, &owners) {
        errors.push(e);
    }
    if let Err(e) = check_words(&l) {
        errors.push(e);
    }
    if errors.is_empty() {
        Ok(l)
    } else {
        Err(errors.join("\n"))
    }
}

/// The whole declaration (panics where [`merged`] refuses it; build.rs reports its errors).
pub fn declared() -> Layout {
    merged().unwrap_or_else(|e| panic!("{e}"))
}
