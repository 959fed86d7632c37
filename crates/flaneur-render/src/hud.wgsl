// The heads-up display: one quad, its texels read one for one (no filtering, so the
// bitmap font stays sharp), blended onto the target by the pipeline.
struct Quad {
    // The quad's corners in clip space: top-left (x, y), bottom-right (z, w).
    rect: vec4<f32>,
    // The target pixel that shows texel (0, 0).
    origin: vec4<f32>,
};
@group(0) @binding(0) var<uniform> quad: Quad;
@group(0) @binding(1) var hud: texture_2d<f32>;

@vertex
fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    // No vertex buffer: the quad's two triangles are made here from its rectangle.
    var corners = array<vec2<f32>, 6>(
        vec2(0.0, 0.0), vec2(1.0, 0.0), vec2(0.0, 1.0),
        vec2(0.0, 1.0), vec2(1.0, 0.0), vec2(1.0, 1.0),
    );
    let c = corners[i];
    return vec4<f32>(mix(quad.rect.xy, quad.rect.zw, c), 0.0, 1.0);
}

@fragment
fn fs(@builtin(position) pixel: vec4<f32>) -> @location(0) vec4<f32> {
    let texel = vec2<i32>(floor(pixel.xy - quad.origin.xy));
    return textureLoad(hud, texel, 0);
}
