//! Tables generated from the registry and the knob table: the README's method table,
//! docs/knobs.md's knob table and `specula knobs` print these, so no list of methods or knobs
//! is written by hand anywhere (tests/readme.rs checks both files against them).

use crate::methods::{Method, ObjectClass};
use crate::quality::KNOBS;

fn serves(m: Method) -> String {
    let all = [ObjectClass::Mirror, ObjectClass::ThinDielectric, ObjectClass::SolidDielectric];
    if all.iter().all(|c| m.can_serve(*c)) {
        return "any".into();
    }
    m.serves.iter().map(|c| c.label()).collect::<Vec<_>>().join(", ")
}

/// The README's method table (Markdown).
pub fn method_table() -> String {
    let mut s = String::from("| `--method` | C ABI | survey | serves | what it does |\n|---|---|---|---|---|\n");
    s += "| `auto` | `SPECULA_METHOD_AUTO` | | any | the measuring planner: per specular object the method with the best predicted error for the frame's predicted time on this device (`specula plan SCENE --candidates` says which, why and what else) |\n";
    for m in Method::ALL {
        let standing = ON_LAVAPIPE.iter().find(|(n, _)| *n == m.name).map_or(String::new(), |(_, s)| format!(". **On lavapipe**: {s}"));
        s += &format!("| `{}` | `SPECULA_METHOD_{}` | {} | {} | {}{standing} |\n", m.name, abi_name(*m), m.section, serves(*m), m.summary);
    }
    s
}

/// Where the approximate methods of issue 35 stand against every other method, the exact
/// ray tracers included, on lavapipe (Mesa 25.0.7, 2 cores): one `specula tradeoff` run per
/// scene, the specular pixels' PSNR against the 16-spp reference and the frame's GPU time
/// (BENCHMARKS.md, "Every approximate method against the exact tracers"); dominated means
/// another method faster beyond the noise (1.12×) and more accurate by over 0.5 dB. Every
/// name is a registered method (`docs` test).
pub const ON_LAVAPIPE: [(&str, &str); 7] = [
    ("curved-reflector", "dominated by proxy-box and distance on builtin:convex-mirror at 128² (24.70 dB in 233 ms against 25.94 in 42)"),
    ("planar-refraction", "dominated by bvh on builtin:flat-glass at 128² (15.88 dB in 115 ms against 28.62 in 100)"),
    ("layered", "dominated by bvh on builtin:concave-occluder at 128² (22.75 dB in 46 ms against 24.10 in 20; the peel, drawn only where a face's layers hold surfaces, 36 ms of it)"),
    ("image-space-refraction", "on the front on builtin:glass-1.5 at 128² with image_space_iterations=2 (24.40 dB in 50 ms; refractor-map 31.70 in 70, ray-query 31.44 in 137); at the paper's 0 iterations 14.86 dB"),
    ("refractor-map", "on the front on builtin:glass-1.5 at 128² (31.70 dB in 70 ms; ray-query 31.44 in 147)"),
    ("distance-multi", "on the front on three mirror balls in mutual view at 128² while nothing moves (maps reused: 25.28 dB in 3.9 ms; bvh 26.84 in 12.5; remade every frame 267 ms); dominated by bvh on assets/mirrors/mirrors.gltf at 128² (22.89 dB against 28.19: one point's distance map fits its flat panels badly, 22.6 dB where planar-mirror gets 29.1)"),
    ("ray-hierarchy", "bvh renders the same image 129× faster on builtin:corner-mirror at 64² (1889 ms against 14.7; the ray engine 788), with its tiles ordered by direction and pixel"),
];

/// The C header's constant name of a method: `SPECULA_METHOD_<NAME>`.
pub fn abi_name(m: Method) -> String {
    m.name.to_uppercase().replace('-', "_")
}

/// docs/knobs.md's knob table (Markdown): name, values, default, doc, and the methods that read it.
pub fn knob_table() -> String {
    let mut s = String::from("| knob | values | default | what it does | read by |\n|---|---|---|---|---|\n");
    for k in KNOBS {
        let readers: Vec<&str> = Method::ALL.iter().filter(|m| m.knobs.contains(&k.name)).map(|m| m.name).collect();
        let readers = if k.name == crate::quality::PlanKnobs::planner {
            "auto".to_string()
        } else if readers.is_empty() {
            "every frame".into()
        } else {
            readers.join(", ")
        };
        s += &format!("| `{}` | {} | {} | {} | {} |\n", k.name, cell(k.values), k.default, cell(k.doc), readers);
    }
    s
}

/// Replaces the text between `<!-- NAME:begin -->` and `<!-- NAME:end -->` in `doc`.
pub fn splice(doc: &str, name: &str, content: &str) -> Option<String> {
    let (b, e) = (format!("<!-- {name}:begin -->\n"), format!("<!-- {name}:end -->"));
    let i = doc.find(&b)? + b.len();
    let j = doc[i..].find(&e)? + i;
    Some(format!("{}{}{}", &doc[..i], content, &doc[j..]))
}

/// A table cell: alternatives written `a|b` in the code read `a, b` in Markdown.
pub fn cell(s: &str) -> String {
    s.replace(" | ", ", ").replace('|', ", ")
}

/// The C header's method constants, generated from the registry (tests/c_header.rs puts
/// them after the includes of include/specula.h).
pub fn c_method_defines() -> String {
    let mut s = String::from("/* Rendering methods (SpeculaMethod), generated from the method registry: the same names\n * as the CLI's --method. SPECULA_METHOD_AUTO lets the planner choose per object. */\n");
    s += &format!(
        "/* the planner: per specular object the method whose rule fits it best */\n#define SPECULA_METHOD_AUTO {}\n",
        crate::methods::registry::ABI_AUTO
    );
    for m in Method::ALL {
        let cpu = if m.is_gpu() { "" } else { " (CPU only: specula_context_configure refuses it)" };
        s += &format!("/* {} ({}){cpu} */\n#define SPECULA_METHOD_{} {}\n", m.name, m.section, abi_name(*m), m.abi);
    }
    s
}

#[cfg(test)]
mod tests {
    /// Every method `ON_LAVAPIPE` names is registered (a typo would drop its standing from
    /// the README's table without a word).
    #[test]
    fn standings_name_registered_methods() {
        for (name, _) in super::ON_LAVAPIPE {
            assert!(crate::plan::Method::parse(name).is_ok(), "{name}");
        }
    }
}
