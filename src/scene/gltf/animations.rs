//! glTF animations into [`Animation`](crate::scene::animation::Animation): every node's rest
//! pose and every translation, rotation and scale channel of every animation (played
//! together). Morph-target weights are skipped with a note; a channel on a node given by a
//! matrix (which the specification forbids) is an error naming it.

use glam::{Quat, Vec3, Vec4};
use gltf::accessor::{DataType, Dimensions};
use gltf::animation::Property;

use super::Importer;
use crate::error::Result;
use crate::scene::animation::{Channel, Interpolation, NodePose, Target};

impl Importer<'_> {
    pub(super) fn import_animations(&mut self) -> Result<()> {
        let doc = self.doc;
        if doc.animations().len() == 0 {
            return Ok(());
        }
        let nodes: Vec<NodePose> = doc
            .nodes()
            .map(|n| match n.transform() {
                gltf::scene::Transform::Matrix { matrix } => NodePose {
                    translation: Vec3::ZERO,
                    rotation: Quat::IDENTITY,
                    scale: Vec3::ONE,
                    matrix: Some(glam::Mat4::from_cols_array_2d(&matrix)),
                },
                gltf::scene::Transform::Decomposed { translation, rotation, scale } => NodePose {
                    translation: Vec3::from(translation),
                    rotation: Quat::from_array(rotation).normalize(),
                    scale: Vec3::from(scale),
                    matrix: None,
                },
            })
            .collect();
        let mut channels = Vec::new();
        let mut skipped = Vec::new();
        for anim in doc.animations() {
            for ch in anim.channels() {
                let field = format!("animations[{}].channels[{}]", anim.index(), ch.index());
                let node = ch.target().node().index();
                let target = match ch.target().property() {
                    Property::Translation => Target::Translation,
                    Property::Rotation => Target::Rotation,
                    Property::Scale => Target::Scale,
                    Property::MorphTargetWeights => {
                        skipped.push(format!("{field}: morph-target weights are not animated"));
                        continue;
                    }
                };
                if nodes[node].matrix.is_some() {
                    return Err(
                        self.err(format!("{field}.target.node"), format!("nodes[{node}] has a matrix, which glTF forbids animating"))
                    );
                }
                let sampler = ch.sampler();
                let interpolation = match sampler.interpolation() {
                    gltf::animation::Interpolation::Step => Interpolation::Step,
                    gltf::animation::Interpolation::Linear => Interpolation::Linear,
                    gltf::animation::Interpolation::CubicSpline => Interpolation::CubicSpline,
                };
                let times = self.read_floats(&sampler.input(), Dimensions::Scalar, &[DataType::F32], &format!("{field}.sampler.input"))?;
                let out_field = format!("{field}.sampler.output");
                let values: Vec<Vec4> = match target {
                    Target::Rotation => {
                        let all = [DataType::F32, DataType::I8, DataType::U8, DataType::I16, DataType::U16];
                        let raw = self.read_floats(&sampler.output(), Dimensions::Vec4, &all, &out_field)?;
                        raw.chunks_exact(4).map(Vec4::from_slice).collect()
                    }
                    _ => {
                        let raw = self.read_floats(&sampler.output(), Dimensions::Vec3, &[DataType::F32], &out_field)?;
                        raw.chunks_exact(3).map(|v| Vec3::from_slice(v).extend(0.0)).collect()
                    }
                };
                let c = Channel { node, target, interpolation, times, values };
                c.validate(&field).map_err(|(f, m)| self.err(f, m))?;
                channels.push(c);
            }
        }
        let duration = channels.iter().filter_map(|c| c.times.last().copied()).fold(0.0, f32::max);
        self.scene.skipped.extend(skipped);
        let anim = self.scene.animation.get_or_insert_with(Default::default);
        anim.nodes = nodes;
        anim.channels = channels;
        anim.duration = duration;
        Ok(())
    }
}
