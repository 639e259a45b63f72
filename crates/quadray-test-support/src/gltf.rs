//! Small glTF files written by tests.

/// A glTF scene of one triangle, without a camera, whose one buffer (the triangle's 36 bytes of
/// positions) is read from `uri`: for the tests of which files a scene may read.
pub fn triangle_with_buffer(uri: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3"}}],
        "bufferViews":[{{"buffer":0,"byteLength":36}}],
        "buffers":[{{"byteLength":36,"uri":"{uri}"}}]}}"#
    )
}
