// Scene data shared by passes that draw meshes (twin: renderer/scene_gpu.rs `ObjectGpu`).

struct Object {
    model: mat4x4f,
    // inverse transpose of model (for normals), 3x3 part used
    normal_matrix: mat4x4f,
    prev_model: mat4x4f,
}
