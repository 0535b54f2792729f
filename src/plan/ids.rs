//! What the plan says about methods without knowing them: a method's id, a whole-scene
//! choice, an object's class, how an object appears in other objects' maps, and how a camera
//! stage's passes are charged. The registry (`methods::registry`) describes what each id
//! means; this file imports nothing of it, so that the plan's data, the frame and the
//! predictors can name methods below the families.

use crate::scene::SurfaceKind;

/// A registered method, by its id: the stable name its family declares it under
/// (`registry::MethodInfo::name`). What the method is — its knobs, maps, camera pass — is the
/// registry's (`methods::ALL`): `Method` dereferences to its `MethodInfo` there.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct Method(pub &'static str);

impl Method {
    pub fn name(self) -> &'static str {
        self.0
    }
}

impl std::fmt::Debug for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0)
    }
}

impl serde::Serialize for Method {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.0)
    }
}

/// A whole-scene choice: one method for every specular object, or the planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub enum Choice {
    Auto,
    Method(Method),
}

impl Choice {
    pub fn name(self) -> &'static str {
        match self {
            Choice::Auto => "auto",
            Choice::Method(m) => m.name(),
        }
    }
}

impl From<Method> for Choice {
    fn from(m: Method) -> Choice {
        Choice::Method(m)
    }
}

/// What kind of specular object a method can serve (survey §1.1).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum ObjectClass {
    /// Ideal mirror (conductor or dielectric reflectance, no transmission).
    Mirror,
    /// Thin-walled dielectric: reflection plus undeviated transmission.
    ThinDielectric,
    /// Solid dielectric: refraction in and out, possibly total internal reflection.
    SolidDielectric,
}

impl ObjectClass {
    pub fn of(kind: &SurfaceKind) -> Option<ObjectClass> {
        match kind {
            SurfaceKind::Diffuse => None,
            SurfaceKind::Mirror { .. } => Some(ObjectClass::Mirror),
            SurfaceKind::Dielectric { thin: true, .. } => Some(ObjectClass::ThinDielectric),
            SurfaceKind::Dielectric { thin: false, .. } => Some(ObjectClass::SolidDielectric),
        }
    }

    pub fn label(self) -> &'static str {
        match self {
            ObjectClass::Mirror => "mirror",
            ObjectClass::ThinDielectric => "thin dielectric",
            ObjectClass::SolidDielectric => "solid dielectric",
        }
    }
}

/// How a specular object appears in the other objects' distance maps (survey §4.3): what
/// the map-generation shader does when it draws it (`map_shading` in `Object`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MapShading {
    /// Reflects and refracts the environment map only (one bounce).
    Sky,
    /// Traced in its own distance map of the previous cycle (inter-object cycles).
    Traced,
    /// Self refraction in its own refractor map, then its own distance map of the previous
    /// cycle (§4.4 composed with §4.3).
    Refractor,
}

impl MapShading {
    /// The code the shaders read (`MAP_SHADING_*`, src/frame/layout.in.rs).
    pub fn code(self) -> u32 {
        use crate::frame::layout::{MAP_SHADING_REFRACTOR, MAP_SHADING_SKY, MAP_SHADING_TRACED};
        match self {
            MapShading::Sky => MAP_SHADING_SKY,
            MapShading::Traced => MAP_SHADING_TRACED,
            MapShading::Refractor => MAP_SHADING_REFRACTOR,
        }
    }
}

/// What an object's own cube maps leave out (survey §3.1: "the object itself left out";
/// §4.5's layered maps keep the whole scene).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum LeavesOut {
    /// The object itself: its maps see the environment around it.
    Itself,
    /// Nothing: its maps see the whole scene, the object included.
    Nothing,
}

/// The timed passes of a method's camera stage, for the budget (`plan::budget`), which
/// charges each timed pass to the objects of the stages that record it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Profiled {
    /// The passes the stage records besides its `name` (and its family's frame work, e.g.
    /// planar mirrors' views) are named with this prefix; `""`: it records `name` only.
    pub prefix: &'static str,
    /// They run over the whole screen whatever the stage serves (a ray tracer's kernels):
    /// paid once per method a frame uses, not split among its objects.
    pub shared: bool,
}

impl Profiled {
    /// One pass under the stage's own name, per object.
    pub const OWN: Profiled = Profiled { prefix: "", shared: false };
}
