//! What Rust and GLSL share, read from its one declaration (src/frame/layout.in.rs) for
//! build.rs (which writes `$OUT_DIR/glsl/generated/layout.glsl`) and for tests/layout.rs.
//!
//! The declaration is a few macro invocations. The crate expands them (src/frame/layout.rs)
//! into `#[repr(C)]` structs and consts; here the same invocations expand into a
//! description ([`Layout`]) from which [`glsl`] writes the GLSL text, after [`check_structs`]
//! has laid every struct out twice, as std430 and as `repr(C)` of the Rust type each field
//! maps to, and refused any field that the two place differently.

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

#[derive(Default)]
pub struct Layout {
    pub structs: Vec<StructDecl>,
    pub consts: Vec<ConstDecl>,
    pub sets: Vec<SetDecl>,
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
        "// Generated by build.rs (build/layout.rs) from src/frame/layout.in.rs, which also gives the\n\
         // Rust side its structs and consts. Do not edit: change the declaration.\n\
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
        for b in &set.bindings {
            comment(&mut out, "", &b.doc);
            let std430 = if b.ty == "STORAGE_BUFFER" || b.ty == "UNIFORM_BUFFER" { "std430, " } else { "" };
            writeln!(out, "layout({std430}set = {}, binding = {}) {};", set.set, b.binding, b.decl).unwrap();
        }
    }
    for s in l.structs.iter().filter(|s| s.kind == "push_constant") {
        out.push('\n');
        comment(&mut out, "", &s.doc);
        writeln!(out, "layout(push_constant) uniform {} {{", s.glsl).unwrap();
        s.fields.iter().for_each(|f| field(&mut out, f));
        writeln!(out, "}} {};", s.instance).unwrap();
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

/// The declaration of src/frame/layout.in.rs as read here.
pub mod declared {
    include!("../src/frame/layout.in.rs");
}

pub fn declared() -> Layout {
    Layout { structs: declared::structs(), consts: declared::consts(), sets: declared::sets() }
}
