//! Pictures of a frame as `quadray indirect` and the viewer show them: tone mapping, the cut over
//! the RSM, and the mean FLIP between two pictures.

use crate::frame::{CutNode, Frame};
use quadray_core::image_out::Rgba8Image;

/// The exposed radiance [`tone_map`] shows as 90% white (1 - e^-2.3): what
/// [`quadray_core::image_out::check_exposure`] calls white for these pictures.
pub const TONE_MAP_WHITE: f32 = 2.3;

/// Exposure, then 1 - exp(-x) and the sRGB curve.
pub fn tone_map(width: u32, height: u32, radiance: &[[f32; 3]], exposure: f32) -> Rgba8Image {
    let encode = |v: f32| {
        let x = 1.0 - (-v.max(0.0) * exposure).exp();
        let s = if x <= 0.003_130_8 {
            12.92 * x
        } else {
            1.055 * x.powf(1.0 / 2.4) - 0.055
        };
        (s.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
    };
    Rgba8Image {
        width,
        height,
        pixels: radiance
            .iter()
            .map(|p| [encode(p[0]), encode(p[1]), encode(p[2]), 255])
            .collect(),
    }
}

/// Outline colours of the cut's clusters by level (0 = single VPLs); `light/cut_view.wgsl` has
/// the same.
const LEVEL_COLOURS: [[u8; 4]; 6] = [
    [255, 255, 255, 255],
    [255, 64, 64, 255],
    [255, 200, 0, 255],
    [64, 220, 64, 255],
    [64, 160, 255, 255],
    [230, 90, 255, 255],
];

/// The magnification at which [`cut_view`] shows an RSM of `rsm_size` texels a side at 512
/// pixels or more.
pub fn cut_view_zoom(rsm_size: u32) -> u32 {
    (512 / rsm_size.max(1)).max(1)
}

/// The selected clusters over the RSM that they cluster: the RSM's flux (level 0 of `nodes`,
/// the pyramid as [`crate::Renderer::read_nodes`] reads it), exposed by its mean over the texels
/// that see geometry (the root's flux over its texel count), magnified `zoom` times, with every
/// cluster of the cut outlined in a colour by its level (white single VPLs, then red, yellow,
/// green, blue, violet going up). The GPU draws the same picture with
/// [`crate::wgsl::CUT_VIEW`] (the Bevy plugin's debug view).
pub fn cut_view(rsm_size: u32, nodes: &[[[f32; 4]; 3]], cut: &[CutNode], zoom: u32) -> Rgba8Image {
    let side = rsm_size * zoom;
    let luminance = |p: &[f32; 4]| quadray_core::image_out::luminance([p[0], p[1], p[2]]);
    let root = nodes.last().map_or([0.0; 4], |n| n[0]);
    let sum = luminance(&root);
    let exposure = if sum > 0.0 { root[3] / sum } else { 1.0 };
    let flux: Vec<[f32; 3]> = nodes[..(rsm_size * rsm_size) as usize]
        .iter()
        .map(|n| [n[0][0], n[0][1], n[0][2]])
        .collect();
    let rsm = tone_map(rsm_size, rsm_size, &flux, exposure);
    let mut image = Rgba8Image {
        width: side,
        height: side,
        pixels: (0..side * side)
            .map(|i| rsm.pixels[((i / side / zoom) * rsm_size + i % side / zoom) as usize])
            .collect(),
    };
    for node in cut {
        let colour = LEVEL_COLOURS[node.level as usize % LEVEL_COLOURS.len()];
        let n = (1 << node.level) * zoom;
        let (x0, y0) = (node.x * n, node.y * n);
        // top and left edges: neighbours draw the others, so every boundary is drawn once
        for i in 0..n.min(side - x0) {
            image.pixels[(y0 * side + x0 + i) as usize] = colour;
        }
        for i in 0..n.min(side - y0) {
            image.pixels[((y0 + i) * side + x0) as usize] = colour;
        }
    }
    image
}

/// Mean FLIP (NVIDIA's perceptual difference, 0 = identical) of `test` against `reference`.
pub fn mean_flip(reference: &Rgba8Image, test: &Rgba8Image) -> f32 {
    let rgb = |img: &Rgba8Image| -> Vec<u8> {
        img.pixels.iter().flat_map(|p| [p[0], p[1], p[2]]).collect()
    };
    let flip_image =
        |img: &Rgba8Image| nv_flip::FlipImageRgb8::with_data(img.width, img.height, &rgb(img));
    let map = nv_flip::flip(
        flip_image(reference),
        flip_image(test),
        nv_flip::DEFAULT_PIXELS_PER_DEGREE,
    );
    nv_flip::FlipPool::from_image(&map).mean()
}

/// The mean FLIP of `frame`'s picture (direct plus indirect light, tone mapped at `exposure`)
/// against the picture with the same direct light and `indirect` instead (a reference's).
pub fn flip_against(frame: &Frame, indirect: &[[f32; 3]], exposure: f32) -> f32 {
    let (w, h) = (frame.width, frame.height);
    let reference = Frame {
        indirect: indirect.to_vec(),
        ..frame.clone()
    };
    mean_flip(
        &tone_map(w, h, &reference.combined(), exposure),
        &tone_map(w, h, &frame.combined(), exposure),
    )
}
