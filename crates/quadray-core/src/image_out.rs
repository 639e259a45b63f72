//! Pictures are the product: PNG output, error heat maps and labelled side-by-side montages.

use crate::FileError;
use font8x8::UnicodeFonts;
use std::path::Path;

/// An 8-bit RGBA image, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Rgba8Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[u8; 4]>,
}

impl Rgba8Image {
    pub fn new(width: u32, height: u32, fill: [u8; 4]) -> Self {
        Self {
            width,
            height,
            pixels: vec![fill; (width * height) as usize],
        }
    }

    pub fn from_bytes(width: u32, height: u32, bytes: &[u8]) -> Self {
        Self {
            width,
            height,
            pixels: bytes
                .chunks_exact(4)
                .map(|p| [p[0], p[1], p[2], p[3]])
                .collect(),
        }
    }

    pub fn save_png(&self, path: &Path) -> Result<(), FileError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|e| FileError::new(dir, e))?;
        }
        image::save_buffer(
            path,
            bytemuck_flat(&self.pixels),
            self.width,
            self.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| FileError::new(path, e))
    }

    fn put(&mut self, x: u32, y: u32, c: [u8; 4]) {
        if x < self.width && y < self.height {
            self.pixels[(y * self.width + x) as usize] = c;
        }
    }

    fn blit(&mut self, src: &Rgba8Image, x0: u32, y0: u32) {
        for y in 0..src.height {
            for x in 0..src.width {
                self.put(x0 + x, y0 + y, src.pixels[(y * src.width + x) as usize]);
            }
        }
    }

    /// Draws `text` with the 8x8 public-domain font at integer `scale`, on a dark box for contrast.
    pub fn label(&mut self, x0: u32, y0: u32, text: &str, scale: u32) {
        let w = text.chars().count() as u32 * 8 * scale;
        for y in y0..y0 + 8 * scale + 2 {
            for x in x0..x0 + w + 2 {
                self.put(x, y, [0, 0, 0, 255]);
            }
        }
        for (i, ch) in text.chars().enumerate() {
            let glyph = font8x8::BASIC_FONTS.get(ch).unwrap_or([0; 8]);
            for (row, bits) in glyph.iter().enumerate() {
                for col in 0..8u32 {
                    if bits >> col & 1 == 1 {
                        for s in 0..scale * scale {
                            self.put(
                                x0 + 1 + (i as u32 * 8 + col) * scale + s % scale,
                                y0 + 1 + row as u32 * scale + s / scale,
                                [255, 255, 255, 255],
                            );
                        }
                    }
                }
            }
        }
    }
}

fn bytemuck_flat(pixels: &[[u8; 4]]) -> &[u8] {
    pixels.as_flattened()
}

/// How far two pictures of one size are apart, channel value by channel value (8-bit): the mean
/// absolute difference, and the fraction of values that differ by more than `far`. Tests hold
/// two renders of one setup to these two figures.
///
/// # Panics
/// When the two differ in length (pictures of different sizes).
pub fn channel_difference(a: &[u8], b: &[u8], far: u8) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "pictures of different sizes");
    let diffs = || a.iter().zip(b).map(|(x, y)| x.abs_diff(*y));
    let count = a.len().max(1) as f64;
    let mean = diffs().map(f64::from).sum::<f64>() / count;
    let far_off = diffs().filter(|&d| d > far).count() as f64 / count;
    (mean, far_off)
}

/// Maps `values` (NaN = no data, drawn dark grey) to a heat map: black at 0 through red and
/// yellow to white at `max`.
pub fn heat_map(width: u32, height: u32, values: &[f32], max: f32) -> Rgba8Image {
    let pixels = values
        .iter()
        .map(|&v| {
            if v.is_nan() {
                return [40, 40, 48, 255];
            }
            let t = (v / max).clamp(0.0, 1.0);
            let ch = |a: f32| ((t * 3.0 - a).clamp(0.0, 1.0) * 255.0) as u8;
            [ch(0.0), ch(1.0), ch(2.0), 255]
        })
        .collect();
    Rgba8Image {
        width,
        height,
        pixels,
    }
}

/// Lays `tiles` (caption, image) out in rows of `columns`, each captioned, on a grey background.
pub fn montage(tiles: &[(String, Rgba8Image)], columns: usize) -> Rgba8Image {
    let columns = columns.max(1);
    let tile_w = tiles.iter().map(|(_, t)| t.width).max().unwrap_or(1);
    let tile_h = tiles.iter().map(|(_, t)| t.height).max().unwrap_or(1);
    let caption = 14;
    let gap = 4;
    let rows = tiles.len().div_ceil(columns) as u32;
    let mut out = Rgba8Image::new(
        columns as u32 * (tile_w + gap) + gap,
        rows * (tile_h + caption + gap) + gap,
        [90, 90, 90, 255],
    );
    for (i, (text, tile)) in tiles.iter().enumerate() {
        let x = gap + (i % columns) as u32 * (tile_w + gap);
        let y = gap + (i / columns) as u32 * (tile_h + caption + gap);
        out.label(x, y, text, 1);
        out.blit(tile, x, y + caption);
    }
    out
}

/// The values an exposure (a radiance scale before tone mapping) may take.
pub const EXPOSURE: crate::settings::Limits<f32> = crate::settings::Limits::above(0.0, 1e12);

/// A linear picture that its exposure shows nearly black or nearly white, and the exposure that
/// would show it: photometric lights (a glTF spot's candela) and a scene's scale make radiance
/// differ by orders of magnitude between scenes, and a black picture alone says nothing.
#[derive(Clone, Debug, PartialEq)]
pub struct ExposureAdvice {
    /// What is wrong, in words.
    pub problem: String,
    /// The exposure that brings the picture's 99th-percentile luminance to 80% of white (none
    /// where the picture is black everywhere: no exposure shows it).
    pub suggested: Option<f32>,
}

impl std::fmt::Display for ExposureAdvice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.suggested {
            Some(e) => write!(f, "{}: try --exposure {e}", self.problem),
            None => f.write_str(&self.problem),
        }
    }
}

/// The Rec. 709 weights of linear RGB's luminance: the one measure of a colour's size that the
/// pictures' exposure, the per-tile cuts' rules (the indirect shaders' prelude declares them), their
/// twin, the studies and the scenes' lighting advice use.
pub const LUMINANCE: [f64; 3] = [0.2126, 0.7152, 0.0722];

/// The luminance of linear RGB `rgb` in f32 ([`LUMINANCE`] rounded to f32), as the shaders weigh
/// it.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    let [r, g, b] = LUMINANCE.map(|w| w as f32);
    r * rgb[0] + g * rgb[1] + b * rgb[2]
}

/// The picture of linear `radiance` at `exposure` judged by its 99th-percentile and median
/// luminance: nearly black where 99% of the pixels are below 2% of `white` (the exposed value
/// the tone map shows as white), nearly white where half of them are at or above `white`.
pub fn check_exposure(radiance: &[[f32; 3]], exposure: f32, white: f32) -> Option<ExposureAdvice> {
    let mut luminance: Vec<f32> = radiance
        .iter()
        .map(|p| luminance(*p))
        .filter(|l| l.is_finite())
        .map(|l| l.max(0.0))
        .collect();
    if luminance.is_empty() {
        return None;
    }
    luminance.sort_by(f32::total_cmp);
    let at = |q: f64| luminance[((luminance.len() - 1) as f64 * q).round() as usize];
    let (p99, median) = (at(0.99), at(0.5));
    if p99 <= 0.0 {
        return Some(ExposureAdvice {
            problem: "the picture is black: no light reaches what the camera sees".into(),
            suggested: None,
        });
    }
    let problem = if p99 * exposure < 0.02 * white {
        "the picture is nearly black (99% of its pixels below 2% of white)"
    } else if median * exposure >= white {
        "the picture is nearly white (half of its pixels at white)"
    } else {
        return None;
    };
    let suggested = 0.8 * white / p99;
    Some(ExposureAdvice {
        problem: problem.into(),
        suggested: Some(two_digits(suggested)),
    })
}

/// `x` rounded to two significant digits (an exposure a person types).
fn two_digits(x: f32) -> f32 {
    format!("{x:.1e}").parse().unwrap_or(x)
}

/// The command-line parser of a file a program writes (`--out`, `--stats`), so that a wrong name
/// fails before any work: its name ends in one of `extensions` (any name where none are given),
/// which choose the format, and its folder exists (none is made: a mistyped one would scatter
/// the results).
pub fn output_file(
    extensions: &'static [&'static str],
) -> impl Fn(&str) -> Result<std::path::PathBuf, String> + Clone + Send + Sync + 'static {
    move |text: &str| {
        let path = std::path::PathBuf::from(text);
        let extension = path.extension().and_then(|e| e.to_str());
        if !extensions.is_empty()
            && !extension.is_some_and(|e| extensions.iter().any(|x| e.eq_ignore_ascii_case(x)))
        {
            let names: Vec<String> = extensions.iter().map(|e| format!(".{e}")).collect();
            return Err(format!(
                "the format is chosen by the name's ending: one of {}",
                names.join(", ")
            ));
        }
        match path.parent().filter(|d| !d.as_os_str().is_empty()) {
            Some(dir) if !dir.is_dir() => Err(format!(
                "the folder {} does not exist (make it first)",
                dir.display()
            )),
            _ => Ok(path),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exposure_advice_names_an_exposure_that_shows_the_picture() {
        // a ramp 0..1e-3: black at exposure 1, right at the suggested one
        let dim: Vec<[f32; 3]> = (0..1000).map(|i| [i as f32 * 1e-6; 3]).collect();
        let advice = check_exposure(&dim, 1.0, 1.0).unwrap();
        assert!(advice.problem.contains("nearly black"), "{advice}");
        let e = advice.suggested.unwrap();
        assert_eq!(e, 810.0, "0.8 / 0.000989, two digits");
        assert!(check_exposure(&dim, e, 1.0).is_none());
        assert!(advice.to_string().ends_with("try --exposure 810"));
        // half the pixels saturated
        let bright: Vec<[f32; 3]> = (0..100).map(|i| [i as f32; 3]).collect();
        let advice = check_exposure(&bright, 1.0, 2.3).unwrap();
        assert!(advice.problem.contains("nearly white"), "{advice}");
        assert!(check_exposure(&bright, advice.suggested.unwrap(), 2.3).is_none());
        // nothing lit: no exposure helps; NaN pixels are ignored
        let black = vec![[0.0; 3], [f32::NAN; 3]];
        assert_eq!(check_exposure(&black, 1.0, 1.0).unwrap().suggested, None);
    }

    #[test]
    fn heat_map_runs_black_to_white_and_marks_missing_data() {
        let img = heat_map(3, 1, &[0.0, 2.0, f32::NAN], 2.0);
        assert_eq!(img.pixels[0], [0, 0, 0, 255]);
        assert_eq!(img.pixels[1], [255, 255, 255, 255]);
        assert_eq!(img.pixels[2], [40, 40, 48, 255]);
    }

    #[test]
    fn montage_places_every_tile_below_its_caption() {
        let red = Rgba8Image::new(4, 4, [255, 0, 0, 255]);
        let m = montage(&[("a".into(), red.clone()), ("b".into(), red)], 2);
        assert_eq!(m.width, 2 * (4 + 4) + 4);
        // first pixel of the first tile sits below the 14-pixel caption band
        assert_eq!(
            m.pixels[((4 + 14) * m.width + 4) as usize],
            [255, 0, 0, 255]
        );
    }
}
