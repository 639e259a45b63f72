//! Skinned meshes posed on the CPU as Bevy's vertex shader poses them (`bevy_pbr`'s `skin.rs`
//! and `skinning.wgsl`), so that the RSM and the occupancy grid hold what Bevy draws.

use bevy::asset::AssetEvent;
use bevy::ecs::system::SystemParam;
use bevy::mesh::VertexAttributeValues;
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::platform::collections::HashSet;
use bevy::prelude::*;

/// What skinned meshes are posed from: their joints' transforms and inverse bindposes, and what
/// of these changed.
#[derive(SystemParam)]
pub(super) struct Skins<'w, 's> {
    skins: Query<'w, 's, (Entity, Ref<'static, SkinnedMesh>), With<Mesh3d>>,
    joints: Query<'w, 's, Ref<'static, GlobalTransform>>,
    removed: RemovedComponents<'w, 's, SkinnedMesh>,
    bindposes: Res<'w, Assets<SkinnedMeshInverseBindposes>>,
    pub(super) bindpose_events: MessageReader<'w, 's, AssetEvent<SkinnedMeshInverseBindposes>>,
}

impl Skins<'_, '_> {
    /// The entities to pose anew: a joint's transform changed, their skin was added, changed or
    /// taken off, or its inverse bindposes are among the `changed_bindposes` (a frame where
    /// nothing moved finds none).
    pub(super) fn changed(
        &mut self,
        changed_bindposes: &HashSet<AssetId<SkinnedMeshInverseBindposes>>,
    ) -> Vec<Entity> {
        let mut changed: Vec<Entity> = self.removed.read().collect();
        changed.extend(self.skins.iter().filter_map(|(entity, skin)| {
            let moved = skin.is_changed()
                || changed_bindposes.contains(&skin.inverse_bindposes.id())
                || skin
                    .joints
                    .iter()
                    .any(|&j| self.joints.get(j).is_ok_and(|t| t.is_changed()));
            moved.then_some(entity)
        }));
        changed
    }

    /// `mesh` posed by `entity`'s skin, in world space (Bevy ignores the skinned entity's own
    /// transform): each vertex by the sum over its four joints of weight times (the joint's
    /// `GlobalTransform` times its inverse bindpose), its normal by the inverse transpose of that
    /// sum. A joint Bevy has no matrix for (its entity gone, its inverse bindpose missing) is the
    /// identity, as in Bevy. `None` where `entity` has no skin or `mesh` no joint attributes:
    /// Bevy draws it unskinned.
    pub(super) fn posed(&self, entity: Entity, mesh: &Mesh) -> Option<Mesh> {
        let (_, skin) = self.skins.get(entity).ok()?;
        let (
            Some(VertexAttributeValues::Uint16x4(indices)),
            Some(VertexAttributeValues::Float32x4(weights)),
            Some(VertexAttributeValues::Float32x3(positions)),
        ) = (
            mesh.attribute(Mesh::ATTRIBUTE_JOINT_INDEX),
            mesh.attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT),
            mesh.attribute(Mesh::ATTRIBUTE_POSITION),
        )
        else {
            return None;
        };
        if indices.len() != positions.len() || weights.len() != positions.len() {
            return None;
        }
        let inverse_bindposes = self.bindposes.get(&skin.inverse_bindposes);
        let joint_matrices: Vec<Mat4> = skin
            .joints
            .iter()
            .enumerate()
            .map(|(i, &joint)| {
                match (
                    inverse_bindposes.and_then(|b| b.get(i)),
                    self.joints.get(joint),
                ) {
                    (Some(inverse_bindpose), Ok(transform)) => {
                        Mat4::from(transform.affine()) * *inverse_bindpose
                    }
                    _ => Mat4::IDENTITY,
                }
            })
            .collect();
        let blended: Vec<Mat4> = indices
            .iter()
            .zip(weights)
            .map(|(joints, weights)| {
                joints
                    .iter()
                    .zip(weights)
                    .map(|(&j, &w)| {
                        w * joint_matrices
                            .get(usize::from(j))
                            .copied()
                            .unwrap_or(Mat4::IDENTITY)
                    })
                    .fold(Mat4::ZERO, |sum, m| sum + m)
            })
            .collect();
        let mut posed = mesh.clone();
        let moved: Vec<[f32; 3]> = positions
            .iter()
            .zip(&blended)
            .map(|(p, m)| m.transform_point3(Vec3::from(*p)).to_array())
            .collect();
        posed.insert_attribute(Mesh::ATTRIBUTE_POSITION, moved);
        if let Some(VertexAttributeValues::Float32x3(normals)) =
            mesh.attribute(Mesh::ATTRIBUTE_NORMAL)
        {
            // (normalized where the triangles are made)
            let turned: Vec<[f32; 3]> = normals
                .iter()
                .zip(&blended)
                .map(|(n, m)| {
                    let inverse_transpose = Mat3::from_mat4(*m).inverse().transpose();
                    (inverse_transpose * Vec3::from(*n)).to_array()
                })
                .collect();
            posed.insert_attribute(Mesh::ATTRIBUTE_NORMAL, turned);
        }
        Some(posed)
    }
}
