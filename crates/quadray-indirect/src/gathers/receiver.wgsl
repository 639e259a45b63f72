// A receiver of indirect light: what a G-buffer texel holds. Engine-neutral: the including
// shader reads its own G-buffer into it.
struct Receiver {
    // world position
    x: vec3<f32>,
    // unit normal, turned towards the viewer
    n: vec3<f32>,
    // diffuse albedo the gathered light is multiplied by
    albedo: vec3<f32>,
    // whether the texel sees geometry (no light where not)
    covered: bool,
}
