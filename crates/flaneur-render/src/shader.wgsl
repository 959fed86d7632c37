// One pass draws colour and object ids: flat-shaded by a fixed sun, each object its own
// tint (from its id, so that it looks the same whatever slot it has); the id target
// holds the draw slot + 1 (0 is the sky, and the ground, whose slot is the largest u32).
// Everything fades into the sky with the distance across the ground from the eye, so
// that a wall fades as evenly as the ground at its foot; past the fade's end nothing
// shows, in the id target either.
struct Globals {
    view_proj: mat4x4<f32>,
    sun: vec4<f32>,
    sky: vec4<f32>,
    // The eye's x and z, where the fade starts and where it ends (below 0: no fade).
    fade: vec4<f32>,
};
@group(0) @binding(0) var<uniform> globals: Globals;

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) normal: vec3<f32>,
    @location(1) @interpolate(flat) slot: u32,
    @location(2) @interpolate(flat) key: u32,
    @location(3) world: vec3<f32>,
};

@vertex
fn vs(
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) slot: u32,
    @location(3) key: u32,
) -> VertexOut {
    var out: VertexOut;
    out.clip = globals.view_proj * vec4<f32>(position, 1.0);
    out.normal = normal;
    out.slot = slot;
    out.key = key;
    out.world = position;
    return out;
}

struct FragmentOut {
    @location(0) colour: vec4<f32>,
    @location(1) id: u32,
};

fn tint(key: u32) -> vec3<f32> {
    // A cheap integer hash to a pale colour.
    var h = key * 2654435761u;
    h = h ^ (h >> 15u);
    let r = f32(h & 255u) / 255.0;
    let g = f32((h >> 8u) & 255u) / 255.0;
    let b = f32((h >> 16u) & 255u) / 255.0;
    return vec3<f32>(0.55, 0.55, 0.55) + 0.35 * vec3<f32>(r, g, b);
}

@fragment
fn fs(in: VertexOut, @builtin(front_facing) front: bool) -> FragmentOut {
    var n = normalize(in.normal);
    if (!front) {
        n = -n;
    }
    let light = 0.35 + 0.65 * max(dot(n, globals.sun.xyz), 0.0);
    var base = tint(in.key);
    if (in.slot == 0xffffffffu) {
        base = vec3<f32>(0.30, 0.32, 0.28);
    }
    var haze = 0.0;
    if (globals.fade.w >= 0.0) {
        let across = distance(in.world.xz, globals.fade.xy);
        let span = max(globals.fade.w - globals.fade.z, 1e-3);
        haze = smoothstep(0.0, 1.0, (across - globals.fade.z) / span);
    }
    var out: FragmentOut;
    out.colour = vec4<f32>(mix(base * light, globals.sky.rgb, haze), 1.0);
    out.id = select(in.slot + 1u, 0u, haze >= 1.0);
    return out;
}
