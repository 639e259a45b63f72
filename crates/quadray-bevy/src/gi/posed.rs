//! Skinned and morphed meshes posed on the CPU as Bevy's vertex shader poses them (`bevy_pbr`'s
//! `skin.rs`, `skinning.wgsl`, `morph.rs` and `mesh.wgsl`), so that the RSM and the occupancy
//! grid hold what Bevy draws.

use bevy::asset::AssetEvent;
use bevy::ecs::system::SystemParam;
use bevy::mesh::VertexAttributeValues;
use bevy::mesh::morph::{MeshMorphWeights, MorphWeights};
use bevy::mesh::skinning::{SkinnedMesh, SkinnedMeshInverseBindposes};
use bevy::platform::collections::HashSet;
use bevy::prelude::*;

/// What skinned and morphed meshes are posed from: their joints' transforms and inverse
/// bindposes, their morph weights, and what of these changed.
#[derive(SystemParam)]
pub(super) struct Poses<'w, 's> {
    skins: Query<'w, 's, (Entity, Ref<'static, SkinnedMesh>), With<Mesh3d>>,
    joints: Query<'w, 's, Ref<'static, GlobalTransform>>,
    removed: RemovedComponents<'w, 's, SkinnedMesh>,
    bindposes: Res<'w, Assets<SkinnedMeshInverseBindposes>>,
    pub(super) bindpose_events: MessageReader<'w, 's, AssetEvent<SkinnedMeshInverseBindposes>>,
    morphs: Query<'w, 's, (Entity, Ref<'static, MeshMorphWeights>), With<Mesh3d>>,
    /// The weights a `MeshMorphWeights::Reference` names (the glTF node's).
    weights: Query<'w, 's, Ref<'static, MorphWeights>>,
    removed_morphs: RemovedComponents<'w, 's, MeshMorphWeights>,
}

/// A mesh posed: in world space (skinned: Bevy ignores the entity's transform), or in the
/// entity's own space (morphed alone).
pub(super) struct Posed {
    pub(super) mesh: Mesh,
    pub(super) in_world: bool,
}

impl Poses<'_, '_> {
    /// The entities to pose anew: a joint's transform changed, their skin was added, changed or
    /// taken off, or its inverse bindposes are among the `changed_bindposes`; their morph
    /// weights were added, changed or taken off (a frame where nothing moved finds none).
    pub(super) fn changed(
        &mut self,
        changed_bindposes: &HashSet<AssetId<SkinnedMeshInverseBindposes>>,
    ) -> Vec<Entity> {
        let mut changed: Vec<Entity> = self.removed.read().collect();
        changed.extend(self.removed_morphs.read());
        changed.extend(self.skins.iter().filter_map(|(entity, skin)| {
            let moved = skin.is_changed()
                || changed_bindposes.contains(&skin.inverse_bindposes.id())
                || skin
                    .joints
                    .iter()
                    .any(|&j| self.joints.get(j).is_ok_and(|t| t.is_changed()));
            moved.then_some(entity)
        }));
        changed.extend(self.morphs.iter().filter_map(|(entity, morph)| {
            let moved = morph.is_changed()
                || match *morph {
                    MeshMorphWeights::Reference(node) => {
                        self.weights.get(node).is_ok_and(|w| w.is_changed())
                    }
                    MeshMorphWeights::Value { .. } => false,
                };
            moved.then_some(entity)
        }));
        changed
    }

    /// `mesh` as Bevy draws it for `entity`: morphed by its weights (each target's position and
    /// normal differences times its weight added, a weight of 0 skipped), then skinned, in world
    /// space, by the sum over each vertex's four joints of weight times (the joint's
    /// `GlobalTransform` times its inverse bindpose), its normal by the inverse transpose of that
    /// sum. A joint Bevy has no matrix for (its entity gone, its inverse bindpose missing) is the
    /// identity, as in Bevy. `None` where `entity` has neither skin (with the mesh's joint
    /// attributes) nor morph weights (with the mesh's targets): Bevy draws the mesh as it is.
    pub(super) fn posed(&self, entity: Entity, mesh: &Mesh) -> Option<Posed> {
        let morph = self.morph_weights(entity).zip(mesh.get_morph_targets());
        let skin = self.blended_joints(entity, mesh);
        if morph.is_none() && skin.is_none() {
            return None;
        }
        let Some(VertexAttributeValues::Float32x3(positions)) =
            mesh.attribute(Mesh::ATTRIBUTE_POSITION)
        else {
            return None;
        };
        let mut positions: Vec<Vec3> = positions.iter().map(|p| Vec3::from(*p)).collect();
        let mut normals: Option<Vec<Vec3>> = match mesh.attribute(Mesh::ATTRIBUTE_NORMAL) {
            Some(VertexAttributeValues::Float32x3(n)) if n.len() == positions.len() => {
                Some(n.iter().map(|n| Vec3::from(*n)).collect())
            }
            _ => None,
        };
        if let Some((weights, targets)) = morph {
            let count = positions.len();
            for (target, &weight) in weights.iter().enumerate() {
                let Some(differences) = targets.get(target * count..(target + 1) * count) else {
                    continue;
                };
                if weight == 0.0 {
                    continue;
                }
                for (p, d) in positions.iter_mut().zip(differences) {
                    *p += weight * d.position;
                }
                for (n, d) in normals.iter_mut().flatten().zip(differences) {
                    *n += weight * d.normal;
                }
            }
        }
        if let Some(blended) = &skin {
            for (p, m) in positions.iter_mut().zip(blended) {
                *p = m.transform_point3(*p);
            }
            // (normalized where the triangles are made)
            for (n, m) in normals.iter_mut().flatten().zip(blended) {
                *n = Mat3::from_mat4(*m).inverse().transpose() * *n;
            }
        }
        let mut posed = mesh.clone();
        let array = |v: Vec<Vec3>| v.iter().map(Vec3::to_array).collect::<Vec<_>>();
        posed.insert_attribute(Mesh::ATTRIBUTE_POSITION, array(positions));
        if let Some(normals) = normals {
            posed.insert_attribute(Mesh::ATTRIBUTE_NORMAL, array(normals));
        }
        Some(Posed {
            mesh: posed,
            in_world: skin.is_some(),
        })
    }

    /// `entity`'s morph weights (its own, or those of the node it refers to), where it has some.
    fn morph_weights(&self, entity: Entity) -> Option<&[f32]> {
        let (_, morph) = self.morphs.get(entity).ok()?;
        match morph.into_inner() {
            MeshMorphWeights::Value { weights } => Some(weights),
            MeshMorphWeights::Reference(node) => self
                .weights
                .get(*node)
                .ok()
                .map(|w| w.into_inner().weights()),
        }
    }

    /// Each vertex's blend of its joints' matrices, where `entity` has a skin and `mesh` the
    /// joint attributes.
    fn blended_joints(&self, entity: Entity, mesh: &Mesh) -> Option<Vec<Mat4>> {
        let (_, skin) = self.skins.get(entity).ok()?;
        let (
            Some(VertexAttributeValues::Uint16x4(indices)),
            Some(VertexAttributeValues::Float32x4(weights)),
        ) = (
            mesh.attribute(Mesh::ATTRIBUTE_JOINT_INDEX),
            mesh.attribute(Mesh::ATTRIBUTE_JOINT_WEIGHT),
        )
        else {
            return None;
        };
        if indices.len() != weights.len() || indices.len() != mesh.count_vertices() {
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
        let blended = indices
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
        Some(blended)
    }
}
