//! Caustics' knobs (§6).

use crate::quality::knob::knobs;

knobs! {
    /// Caustics (§6).
    pub struct CausticsKnobs {
        /// caustics (§6): photons from each punctual light traced through each caustic generator in its maps, stored as hits in
        /// cube-map space, then splatted (photon splatting) or meshed into caustic triangles (flux over area) into a light cube map
        /// around the generator, filtered, and projected onto diffuse surfaces with a distance test; or (`photon-map`, §6.1.1,
        /// PDC03) sorted into a hashed uniform grid on the GPU and gathered per shaded point from its photon_k nearest photons
        /// within photon_radius (by the camera's diffuse surfaces and the ray tracers' diffuse hits; the map passes do not
        /// gather, so it is missing in cube-map reflections and refractions); the CPU reference adds light-traced caustics
        caustics: Caustics = "triangles", one_of()["off" => Caustics::Off, "splat" => Caustics::Splat, "triangles" => Caustics::Triangles, "photon-map" => Caustics::PhotonMap];
        /// caustics: edge of each photon hit location image (photons² per light and generator view); caustic triangles keep 64
        /// bytes per triangle in one storage buffer, within the device's maxStorageBufferRange (lavapipe's 128 MiB: 1024² photons
        /// for one photon layer, 592² for three)
        photons: u32 = 128, count(32..=2048, "texels");
        /// caustics=splat: radius of each photon's splat (an Epanechnikov kernel normalised to the photon's power) in light-cube
        /// texels (texture space: what that many light-cube texels cover at the photon's distance, 1 to 8 light-map texels)
        splat_size: f32 = 2, real(0.5..=16, "texels");
        /// caustics=photon-map: photons each shaded point gathers (its k nearest on its surface within photon_radius; the
        /// irradiance is their power under an Epanechnikov kernel reaching the (k + 1)-th, or photon_radius where fewer lie
        /// within it): more is smoother and blurs more
        photon_k: u32 = 16, count(1..=64, "photons");
        /// caustics=photon-map: the gather's largest radius and the grid's cell edge, as a fraction of the scene's bounding
        /// diagonal (scale-free: the same at 1 mm and 1 km); photons further than it are never gathered
        photon_radius: f32 = 0.01, real(0.0005..=0.25, "of the diagonal");
        /// caustics: radius of the box filter over each light cube face before projection (0: none)
        caustic_filter: u32 = 1, count(0..=8, "texels");
        /// caustics: a diffuse point takes the light cube map's irradiance only where its distance from the generator matches the
        /// receiver distance map (off: light leaks behind occluders, for comparison)
        caustic_distance_test: bool = "on", one_of()["on" => true, "off" => false];
        /// caustics: the receiver-orientation factor of the projection, E = J·cos α/D² (off: cos α = 1, every receiver taken as
        /// facing the generator; wrong at grazing angles)
        caustic_orientation: bool = "on", one_of()["on" => true, "off" => false];
        /// caustics: photon hits stored and projected in cube-map space, one light cube map per generator around its reference
        /// point (UPSK08), or in light space, one per generator and point or spot light around the light (the shadow-map space of
        /// SP07; directional lights stay in cube-map space): their distance tests leak differently (BENCHMARKS.md); or in screen
        /// space (LC04, WD06b; caustics=splat): splatted straight onto the camera's image of the receivers, depth-tested against
        /// it, so that caustics seen in mirrors or through glass are missing; or in texture space (SKALP05; caustics=splat): each
        /// photon splatted at its receiver's light-map coordinates (an atlas of charts the library cuts, light_map_size²), read
        /// back wherever a pass draws or hits a diffuse surface (not by the curved reflector's virtual objects); it leaks where a
        /// splat's texture-space neighbourhood is hidden from the generator. Needs the device's geometryShader feature
        /// (gl_PrimitiveID in fragment shaders)
        caustic_space: CausticSpace = "cube", one_of()["cube" => CausticSpace::Cube, "light" => CausticSpace::Light, "screen" => CausticSpace::Screen, "texture" => CausticSpace::Texture];
        /// caustic_space=texture: edge of the receivers' light map (one atlas for every diffuse mesh, one texel size for the whole
        /// scene, 16 bytes a texel)
        light_map_size: u32 = 1024, count(64..=8192, "texels");
        /// caustics: a dielectric generator's photons follow both Fresnel branches, each its own photon image (the reflected one is
        /// weak and wide: 4 % at normal incidence), or only the refracted one; mirrors reflect either way. `exact`: photons traced
        /// in the original geometry through Vulkan ray queries (§6.1.1): every specular bounce to the first diffuse hit, a
        /// solid dielectric's paths T·T, R and T·Rᵏ·T (k = 1 … internal_bounces, at most 14) each its own photon image, the
        /// light's visibility by a shadow ray; needs a device with ray queries. `surface`: §6.4's simplified water caustics, a
        /// solid generator's photons refracted once at its surface and on straight to the receivers (searched in the receiver
        /// distance map), never leaving it: for a water body whose floor lies inside it (where the sampled-geometry paths exit
        /// through its bottom, under the floor), no refractor map
        caustic_paths: CausticPaths = "both", one_of()["both" => CausticPaths::Both, "refracted" => CausticPaths::Refracted, "exact" => CausticPaths::Exact, "surface" => CausticPaths::Surface];
    }
}

/// Which paths caustic photons follow, and through what geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CausticPaths {
    /// Both Fresnel branches at the generator's surface, in the sampled geometry (§6.1.2).
    Both,
    /// The refracted branch only.
    Refracted,
    /// Every specular bounce in the original geometry, through ray queries (§6.1.1).
    Exact,
    /// One refraction at a solid generator's surface, then straight on to the receivers
    /// inside it (§6.4: water caustics on a pool's floor).
    Surface,
}

/// The most internal reflections an `exact` photon layer takes (its branch index has 4 bits).
pub const EXACT_MAX_INTERNAL: u32 = 14;

/// Where caustic photon hits are stored and projected from (survey §6.1.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum CausticSpace {
    /// Cube-map space (UPSK08): one cube per generator, around its reference point.
    Cube,
    /// Light space (the shadow-map space of SP07): one cube per generator and point or spot
    /// light, around the light; directional lights stay in cube-map space.
    Light,
    /// Screen space (LC04, WD06b): photons splatted onto the camera's image of the
    /// receivers; only what the camera sees directly gets them.
    Screen,
    /// Texture space (SKALP05): photons splatted into a light map at their receiver's
    /// light-map coordinates.
    Texture,
}

/// How caustics are rendered (survey §6.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Caustics {
    Off,
    /// Photon splatting (§6.3.1).
    Splat,
    /// Caustic triangles (§6.3.2).
    Triangles,
    /// The photon map (§6.1.1, PDC03): photons in a uniform grid built on the GPU, gathered
    /// per shaded point by their k nearest neighbours.
    PhotonMap,
}
