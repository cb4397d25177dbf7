// Relight the representatives of compressed SH light-maps once per frame (Fuchs 2005 §5.8,
// done well): relit[(g·points + k)·reps + r] = Σᵢ repᵣ,ᵢ · l_{g,k,i} (E/π, RGB). The fragment
// shader then filters relit values instead of decompressing per tap.

@group(0) @binding(0) var<uniform> sh_u: ShUniforms;
@group(0) @binding(1) var<storage, read> reps: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> light: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> relit: array<vec4<f32>>;

@compute @workgroup_size(64)
fn relight_cs(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
) {
    let i = id.x + id.y * groups.x * 64u;
    if i >= sh_u.groups * sh_u.points * sh_u.reps {
        return;
    }
    let r = i % sh_u.reps;
    let gk = i / sh_u.reps;
    var e = vec3<f32>(0.0);
    for (var j = 0u; j < sh_u.layers; j++) {
        let t = reps[r * sh_u.layers + j];
        let b = sh_u.coeff_base + gk * 4u * sh_u.layers + 4u * j;
        e += t.x * light[b].xyz + t.y * light[b + 1u].xyz + t.z * light[b + 2u].xyz
            + t.w * light[b + 3u].xyz;
    }
    relit[i] = vec4<f32>(e, 1.0);
}
