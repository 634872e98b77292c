//! V2: the trees' bones in the objects buffer. Each placed tree (its trunk
//! and leaves objects: same rig, same transform) gets a slot of
//! [`BONES`] object records after every other object; `passes/vegetation`
//! writes their world-space bone transforms each frame (record `model` now,
//! `prev_model` the previous frame's) and the tree objects' `params.y =
//! -(1 + first record)` tells the vertex stage where they are
//! (`shaders/object_vertex.wgsl`, `tree_world`). Fixed size: a slot per
//! tree, allocated at upload.

use std::collections::HashMap;

use bytemuck::{Pod, Zeroable};
use glam::Mat4;

use super::ObjectGpu;
use crate::scene::Scene;
use crate::scene::tree::rig::{BONES, MAX_ANGLE, Rig};

/// Largest bend of the trunk bone (rad): a leaning tree, not a falling one.
pub const MAX_TRUNK_ANGLE: f32 = 0.12;
/// Largest bend of a branch bone (rad).
pub const MAX_BRANCH_ANGLE: f32 = 0.2;
const _: () = assert!(MAX_BRANCH_ANGLE <= MAX_ANGLE);

/// Twin of `RigBone` in `passes/vegetation/simulate.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct RigBoneGpu {
    /// Pivot (tree space, m); w: length (m).
    pub pivot: [f32; 4],
    /// Wind sample point (tree space, m); w: gain (rad per (m/s)^2).
    pub sample: [f32; 4],
    /// Natural angular frequency (rad/s), damping ratio, largest angle
    /// (rad), 1 / tree height (1/m).
    pub dynamics: [f32; 4],
}

/// Twin of `Slot` in `passes/vegetation/simulate.wgsl`: the object whose
/// `model` places the tree, its rig (index of its first [`RigBoneGpu`] /
/// BONES) and its first bone record.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Pod, Zeroable)]
pub struct SlotGpu {
    /// Object index (trunk or leaves; both share the transform).
    pub object: u32,
    /// Rig index.
    pub rig: u32,
    /// First of its BONES object records.
    pub first_record: u32,
    /// Unused.
    pub pad: u32,
}

/// The GPU rig bones of `rig`.
pub fn rig_gpu(rig: &Rig) -> [RigBoneGpu; BONES] {
    std::array::from_fn(|b| {
        let bone = &rig.bones[b];
        let max = if b == 0 {
            MAX_TRUNK_ANGLE
        } else {
            MAX_BRANCH_ANGLE
        };
        RigBoneGpu {
            pivot: bone.pivot.extend(bone.length).to_array(),
            sample: bone.sample.extend(bone.gain).to_array(),
            dynamics: [bone.omega, bone.damping, max, 1.0 / rig.height],
        }
    })
}

/// The trees of an upload: slots, rigs, and where the records start.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TreeLayout {
    /// One per placed tree.
    pub slots: Vec<SlotGpu>,
    /// BONES per rig (the scene's `tree_rigs` order).
    pub rigs: Vec<RigBoneGpu>,
    /// Object index of the first bone record.
    pub first_record: u32,
}

/// The rig index of each scene mesh (`None`: no bones).
pub fn mesh_rigs(scene: &Scene) -> Vec<Option<u32>> {
    let mut out = vec![None; scene.meshes.len()];
    for (r, sr) in scene.tree_rigs.iter().enumerate() {
        for &m in &sr.meshes {
            if let Some(o) = out.get_mut(m) {
                *o = Some(r as u32);
            }
        }
    }
    out
}

/// Gives every tree object of `placed` (GPU index, scene object index) a
/// slot (trunk and leaves of one tree: the same one), points its
/// `params.y` at the slot's records, and appends the records (at rest:
/// the tree's transform) to `objects`.
pub(super) fn layout(
    scene: &Scene,
    placed: &[(usize, usize)],
    objects: &mut Vec<ObjectGpu>,
) -> TreeLayout {
    let rigs = mesh_rigs(scene);
    let first_record = objects.len() as u32;
    let mut slots: Vec<SlotGpu> = Vec::new();
    let mut rest: Vec<Mat4> = Vec::new();
    let mut by_key: HashMap<(u32, [u32; 16]), u32> = HashMap::new();
    for &(gpu, si) in placed {
        let o = &scene.objects[si];
        let Some(Some(rig)) = rigs.get(o.mesh).copied() else {
            continue;
        };
        let key = (rig, o.transform.to_cols_array().map(f32::to_bits));
        let slot = *by_key.entry(key).or_insert_with(|| {
            slots.push(SlotGpu {
                object: gpu as u32,
                rig,
                first_record: first_record + (slots.len() * BONES) as u32,
                pad: 0,
            });
            rest.push(o.transform);
            slots.len() as u32 - 1
        });
        let record = slots[slot as usize].first_record;
        objects[gpu].params[1] = -(record as f32 + 1.0);
    }
    for (s, m) in slots.iter().zip(&rest) {
        let inv_h = 1.0 / scene.tree_rigs[s.rig as usize].rig.height;
        for _ in 0..BONES {
            objects.push(ObjectGpu::new(*m, *m, [inv_h, 0.0, 0.0, 0.0]));
        }
    }
    TreeLayout {
        slots,
        rigs: scene
            .tree_rigs
            .iter()
            .flat_map(|r| rig_gpu(&r.rig))
            .collect(),
        first_record,
    }
}

/// The slots' GPU buffers (`None` without trees).
pub struct TreeBuffers {
    /// [`SlotGpu`] per tree.
    pub slots: wgpu::Buffer,
    /// [`RigBoneGpu`] per rig bone.
    pub rigs: wgpu::Buffer,
    /// Per slot and bone: the bend angle (x, z; rad) and its rate (rad/s).
    pub state: wgpu::Buffer,
}

impl TreeBuffers {
    /// Buffers for `layout` (state zero: the first frame resets it).
    pub(super) fn new(device: &wgpu::Device, layout: &TreeLayout) -> Option<Self> {
        use wgpu::util::DeviceExt;
        if layout.slots.is_empty() {
            return None;
        }
        let init = |label, contents: &[u8], usage| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage,
            })
        };
        let state = vec![[0.0f32; 4]; layout.slots.len() * BONES];
        Some(TreeBuffers {
            slots: init(
                "trees.slots",
                bytemuck::cast_slice(&layout.slots),
                wgpu::BufferUsages::STORAGE,
            ),
            rigs: init(
                "trees.rigs",
                bytemuck::cast_slice(&layout.rigs),
                wgpu::BufferUsages::STORAGE,
            ),
            state: init(
                "trees.state",
                bytemuck::cast_slice(&state),
                wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            ),
        })
    }
}
