//! The method registry and one module per family of the survey, mirroring `glsl/`: each
//! family describes its methods once (`registry::MethodInfo`) and owns the passes that
//! make their maps. The frame's own passes (upload, shadows, direct light, the camera
//! passes' machinery) live in `crate::frame`.
//!
//! Adding a method: its descriptor and passes in its family's folder, its shaders in
//! `glsl/<family>/`, its tests, and its name in its family's `FAMILY`. Adding a family: its
//! folders, its tests, `pub mod` and one line of `FAMILIES` below (with knobs, one line of
//! `quality::compose!`; with GPU declarations, one of `build/layout.rs`'s `declarations!`).

pub mod caustics;
pub mod cube_knobs;
pub mod cube_maps;
pub mod distance;
pub mod envmap;
pub mod geometry;
pub mod layered;
pub mod raytrace;
pub mod reference;
pub mod registry;

pub use distance::{DISTANCE, DISTANCE_MULTI, IMAGE_SPACE_REFRACTION, REFRACTOR_MAP};
pub use envmap::{ENVMAP, IMAGE_BASED, PROXY_BOX, PROXY_RELIEF, PROXY_SPHERE};
pub use geometry::{CURVED_REFLECTOR, PLANAR_MIRROR, PLANAR_REFRACTION};
pub use layered::LAYERED;
pub use raytrace::ray_query::RAY_QUERY;
pub use raytrace::{BIH, BVH, GRID, KD_TREE, OCTREE, RAY_ENGINE, RAY_HIERARCHY};
pub use reference::REFERENCE;
pub use registry::{map_named, Choice, Method, MethodInfo, ObjectClass, EVERY_CLASS};

use crate::error::{Error, Result};
use crate::frame::stage::EffectInfo;
use crate::plan::facts::ObjectFacts;

/// Every registered method, family by family (`FAMILIES`), the GPU families first: the CLI's
/// list, `specula knobs`, the C header's constants, the README tables, `tradeoff` and the
/// demo read this.
pub const ALL: &[Method] = &registry::all_methods::<{ registry::method_count(FAMILIES) }>(FAMILIES);

/// Every family, one line each: its methods (in the order `ALL` lists them) and its hooks
/// beyond maps and camera passes, called by the planner and the renderer in this order
/// (their view blocks follow in the view table in this order too).
pub const FAMILIES: &[registry::Family] =
    &[envmap::FAMILY, distance::FAMILY, layered::FAMILY, raytrace::FAMILY, geometry::FAMILY, caustics::FAMILY, reference::FAMILY];

/// Every slot of the frame's maps (`frame::maps`): the frame's own, then each family's
/// (`registry::Family::slots`), the order the camera passes and diffuse shading list their
/// reads in.
pub fn all_slots() -> Vec<&'static crate::frame::maps::Slot> {
    crate::frame::shadow::SLOTS.iter().chain(FAMILIES.iter().flat_map(|f| f.slots.iter())).collect()
}

/// The registry's side of a method id (`plan::types::Method`, which the plan's data holds):
/// its description, found among the families' (the same `&'static str` is compared first,
/// then the name).
impl std::ops::Deref for Method {
    type Target = MethodInfo;
    fn deref(&self) -> &MethodInfo {
        self.info()
    }
}

/// The registry's lookups of a method id.
impl Method {
    /// Every registered method, GPU methods first (`methods::ALL`).
    pub const ALL: &'static [Method] = ALL;

    /// The description its family registered. A `Method` names a registered method by
    /// construction (`FAMILIES`, `parse`, `by_abi`); one that does not is a bug, reported.
    pub fn info(self) -> &'static MethodInfo {
        let every = || FAMILIES.iter().flat_map(|f| f.methods.iter().copied());
        every()
            .find(|i| std::ptr::eq(i.name, self.0))
            .or_else(|| every().find(|i| i.name == self.0))
            .unwrap_or_else(|| panic!("method '{}' is not registered in methods::FAMILIES", self.0))
    }

    /// Whether the method renders on the GPU (through `Renderer`); the reference renders
    /// on the CPU (`reference::render_reference`).
    pub fn is_gpu(self) -> bool {
        self.gpu.is_some()
    }

    pub fn can_serve(self, class: ObjectClass) -> bool {
        self.serves.contains(&class)
    }

    /// Whether it can serve this object: its class and its shape, and for a graded-index
    /// medium whether its rays curve.
    pub fn fits(self, f: &ObjectFacts) -> bool {
        self.can_serve(f.class) && self.shape.fits(f) && (!f.graded || self.traces_curved_rays())
    }

    /// Whether its rays curve through graded media (`Family::curved_rays`).
    pub fn traces_curved_rays(self) -> bool {
        FAMILIES.iter().any(|f| f.curved_rays.contains(&self))
    }

    /// The methods that trace curved rays, by name (the planner's refusals list them).
    pub fn curved_ray_tracers() -> Vec<&'static str> {
        ALL.iter().filter(|m| m.traces_curved_rays()).map(|m| m.name()).collect()
    }

    pub fn parse(s: &str) -> Result<Method> {
        ALL.iter().copied().find(|m| m.name() == s).ok_or_else(|| {
            let names: Vec<_> = ALL.iter().map(|m| m.name()).collect();
            Error::invalid("method", format!("unknown method '{}' (known: auto, {})", crate::error::clip(s), names.join(", ")))
        })
    }

    pub fn by_abi(n: u32) -> Option<Method> {
        ALL.iter().copied().find(|m| m.abi == n)
    }
}

impl Choice {
    pub fn parse(s: &str) -> Result<Choice> {
        if s == "auto" {
            Ok(Choice::Auto)
        } else {
            Method::parse(s).map(Choice::Method)
        }
    }
}

/// The camera pass named `name` (a plan's `CameraPlan`): the first method's that names it.
pub fn camera_named(name: &str) -> Option<registry::CameraPass> {
    ALL.iter().filter_map(|m| m.gpu).map(|g| g.camera).find(|c| c.name == name)
}

/// The frame effect named `name` (a plan's `EffectPlan`), among the families' effects.
pub fn effect_named(name: &str) -> Option<EffectInfo> {
    FAMILIES.iter().flat_map(|f| f.effects.iter()).find(|e| e.name == name).copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn registry_is_consistent() {
        registry::check(&ALL.iter().map(|m| m.info()).collect::<Vec<_>>()).unwrap();
    }

    /// Every slot binds a declared binding of its kind, no two the same, and every map
    /// binding of set 1 (and of set 0 past the frame's own inputs) has a slot, so that
    /// `write_descriptors` leaves none unwritten.
    #[test]
    fn slots_cover_the_map_bindings() {
        let slots = all_slots();
        for (i, s) in slots.iter().enumerate() {
            assert!(!slots[..i].iter().any(|o| o.key() == s.key()), "{} binds a slot already taken", s.name);
            let table = if s.set == 0 { BINDINGS } else { MAP_BINDINGS };
            assert!(s.set <= 1, "{}: slots live in set 0 or 1", s.name);
            let (_, ty, _) = table.iter().find(|b| b.0 == s.binding).unwrap_or_else(|| panic!("{}: no binding {}", s.name, s.binding));
            let want = match s.kind {
                crate::frame::maps::Kind::Image(_) => ash::vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                crate::frame::maps::Kind::Buffer => ash::vk::DescriptorType::STORAGE_BUFFER,
            };
            assert_eq!(*ty, want, "{}", s.name);
            assert!(s.set == 1 || !(s.generation || s.geometry || s.ping_pong || s.needs_pair), "{}: set-1 roles on set 0", s.name);
        }
        for b in MAP_BINDINGS {
            assert!(slots.iter().any(|s| s.key() == (1, b.0)), "set 1 binding {} has no slot", b.0);
        }
        use crate::frame::layout::binding::{ENVIRONMENT_MAP, SHADOW_CUBES};
        use crate::frame::layout::{BINDINGS, MAP_BINDINGS};
        for b in BINDINGS.iter().filter(|b| b.0 > ENVIRONMENT_MAP) {
            assert!(slots.iter().any(|s| s.key() == (0, b.0)), "set 0 binding {} has no slot", b.0);
        }
        assert!(slots.iter().any(|s| s.key() == (0, SHADOW_CUBES)));
    }

    /// A family is its folder plus its registration: every folder under `src/methods/` is a
    /// registered family, and one with knobs has them composed into `Quality` (a forgotten
    /// line fails here; build.rs refuses a forgotten `layout.in.rs` line the same way).
    #[test]
    fn every_family_folder_is_registered() {
        let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
        let quality = std::fs::read_to_string(root.join("src/quality/mod.rs")).unwrap();
        for e in std::fs::read_dir(root.join("src/methods")).unwrap().flatten().filter(|e| e.path().is_dir()) {
            let name = e.file_name().into_string().unwrap();
            assert!(FAMILIES.iter().any(|f| f.name == name), "src/methods/{name}/ is not in methods::FAMILIES");
            if e.path().join("knobs.rs").is_file() {
                assert!(quality.contains(&format!("crate::methods::{name}::knobs::")), "{name}'s knobs are not composed into Quality");
            }
        }
    }

    #[test]
    fn every_method_is_listed_by_its_own_family() {
        for f in FAMILIES {
            for m in f.methods {
                assert_eq!(m.family, f.name, "{} is listed by family {}", m.name, f.name);
            }
        }
        // GPU methods first, the reference last (the CLI's and the README's order).
        let first_cpu = ALL.iter().position(|m| !m.is_gpu()).unwrap();
        assert!(ALL[first_cpu..].iter().all(|m| !m.is_gpu()) && ALL.last() == Some(&REFERENCE));
    }

    #[test]
    fn registry_refuses_duplicates() {
        static COPY: MethodInfo = MethodInfo { name: "distance", abi: 77, ..*distance::DISTANCE_INFO };
        assert!(registry::check(&[distance::DISTANCE_INFO, &COPY]).unwrap_err().contains("named 'distance'"));
        static SAME_NUMBER: MethodInfo = MethodInfo { name: "other", ..*distance::DISTANCE_INFO };
        assert!(registry::check(&[distance::DISTANCE_INFO, &SAME_NUMBER]).unwrap_err().contains("C ABI number"));
        static BAD_KNOB: MethodInfo = MethodInfo { name: "other", abi: 78, knobs: &["warp"], ..*distance::DISTANCE_INFO };
        assert!(registry::check(&[&BAD_KNOB]).unwrap_err().contains("unknown knob"));
    }

    #[test]
    fn registry_refuses_a_method_that_shades_every_pixel_yet_leans_on_others() {
        use registry::GpuSpec;
        const fn whole(g: Option<GpuSpec>) -> Option<GpuSpec> {
            match g {
                Some(g) => Some(GpuSpec { shades_every_pixel: true, ..g }),
                None => None,
            }
        }
        // Maps (and no stage of its own): other passes reach its image.
        static MAPPED: MethodInfo =
            MethodInfo { name: "other", abi: 78, gpu: whole(distance::DISTANCE_INFO.gpu), ..*distance::DISTANCE_INFO };
        assert!(registry::check(&[&MAPPED]).unwrap_err().contains("shades every pixel"));
        // A fallback: its objects are another method's.
        static FALLS_BACK: MethodInfo = MethodInfo { name: "other", abi: 78, fallback: Some(DISTANCE), ..*raytrace::BVH_INFO };
        assert!(registry::check(&[&FALLS_BACK]).unwrap_err().contains("shades every pixel"));
        assert!(BVH.gpu.is_some_and(|g| g.shades_every_pixel) && !DISTANCE.gpu.is_some_and(|g| g.shades_every_pixel));
    }

    #[test]
    fn every_whole_scene_method_covers_every_class() {
        for m in ALL {
            for c in EVERY_CLASS {
                let served = m.can_serve(*c) || m.fallback.is_some_and(|f| f.can_serve(*c));
                assert!(served, "{} leaves a {} without a method", m.name, c.label());
            }
        }
    }
}
