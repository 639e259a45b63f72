//! Height maps in every supported format load as stored; bad maps and parameters get clear errors
//! naming the file and the problem.

use crate::common;

use quadray_core::image_in::MAX_SIDE;
use quadray_displace::heightmap::{Convention, Fit, HeightMap, HeightMapError};
use quadray_displace::maps::load_color;
use quadray_displace::{Layers, Method, Settings, Size};

#[test]
fn odd_sizes_load_as_stored_or_resampled_on_request() {
    let bevy = common::asset("heightmaps/bevy_parallax/cube_depth.png");
    let map = HeightMap::load(&bevy, Convention::Depth, Fit::Exact).unwrap();
    assert_eq!(
        (map.width, map.height, map.padded_size()),
        (348, 348, (512, 512))
    );
    let resampled = HeightMap::load(&bevy, Convention::Depth, Fit::Resample).unwrap();
    assert_eq!((resampled.width, resampled.height), (256, 256));
    let puget = common::asset("heightmaps/puget_sound/ps_height_1k.png");
    let map = HeightMap::load(&puget, Convention::Height, Fit::Resample).unwrap();
    assert_eq!((map.width, map.height), (1024, 1024));
    let photo = common::asset("heightmaps/depth_tum_rgbd/TUM_depth.png");
    let map = HeightMap::load(&photo, Convention::DepthPhoto, Fit::Exact).unwrap();
    assert_eq!((map.padded_size(), map.levels()), ((1024, 512), 10));
}

#[test]
fn sixteen_bit_maps_keep_their_precision() {
    let tiles = common::asset("heightmaps/ambientcg_tiles105/Tiles105_1K_Displacement.png");
    let map = HeightMap::load(&tiles, Convention::Height, Fit::Exact).unwrap();
    let mut levels: Vec<u32> = map
        .depth
        .iter()
        .map(|d| (d * 65535.0).round() as u32)
        .collect();
    levels.sort_unstable();
    levels.dedup();
    assert!(
        levels.len() > 256,
        "only {} distinct depths: quantised to 8 bits?",
        levels.len()
    );
    // SOURCES.md: values 7623..65336, so depth spans (1 - 65336/65535) .. (1 - 7623/65535).
    let max = map.depth.iter().copied().fold(0.0, f32::max);
    assert!((max - (1.0 - 7623.0 / 65535.0)).abs() < 1e-4, "{max}");
}

#[test]
fn nan_empty_and_broken_files_are_refused_with_their_name() {
    let dir = std::env::temp_dir().join(format!("quadray-bad-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let nan = dir.join("nan.exr");
    let mut img = image::Rgb32FImage::new(4, 4);
    img.put_pixel(2, 1, image::Rgb([f32::NAN, 0.0, 0.0]));
    img.save(&nan).unwrap();
    let err = HeightMap::load(&nan, Convention::Height, Fit::Exact).unwrap_err();
    assert!(
        matches!(err, HeightMapError::NotFinite { x: 2, y: 1, .. }),
        "{err}"
    );
    assert!(err.to_string().contains("nan.exr"));

    let empty = dir.join("empty.png");
    std::fs::write(&empty, b"").unwrap();
    let truncated = dir.join("truncated.png");
    let bytes = std::fs::read(common::asset("heightmaps/bevy_parallax/cube_depth.png")).unwrap();
    std::fs::write(&truncated, &bytes[..bytes.len() / 3]).unwrap();
    let text = common::asset("SOURCES.md");
    for path in [empty, truncated, text, dir.join("missing.png")] {
        let err = HeightMap::load(&path, Convention::Height, Fit::Exact).unwrap_err();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        assert!(err.to_string().contains(&name), "{err}");
    }
}

/// A PNG whose header claims 60000x60000 (the data of a few bytes) is refused by quadray's own
/// limit, with the size it read, before a texel is decoded; the albedo loader says the same.
#[test]
fn oversized_headers_are_refused_before_decoding() {
    let chunk = |kind: &[u8; 4], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        c.extend(kind);
        c.extend(data);
        c.extend(crc32fast::hash(&c[4..]).to_be_bytes());
        c
    };
    let side = 60_000u32.to_be_bytes();
    // 8-bit greyscale, deflate, no filter, not interlaced
    let ihdr = [&side[..], &side, &[8, 0, 0, 0, 0]].concat();
    let empty_zlib = [0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01];
    let png = [
        b"\x89PNG\r\n\x1a\n".to_vec(),
        chunk(b"IHDR", &ihdr),
        chunk(b"IDAT", &empty_zlib),
        chunk(b"IEND", &[]),
    ]
    .concat();
    let dir = std::env::temp_dir().join(format!("quadray-huge-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.png");
    std::fs::write(&path, png).unwrap();
    let expected = format!(
        "{}: the image is 60000x60000, over quadray's limit of {MAX_SIDE}x{MAX_SIDE}",
        path.display()
    );
    let err = HeightMap::load(&path, Convention::Height, Fit::Exact).unwrap_err();
    assert_eq!(err.to_string(), expected);
    assert_eq!(load_color(&path).unwrap_err().to_string(), expected);
}

/// Each refusal names the parameter, its value and its range.
#[test]
fn absurd_parameters_are_refused() {
    let ok = Settings::default();
    assert!(ok.validate().is_ok());
    let layers = |min, max| {
        let c = Layers::COUNT;
        format!(
            "layers {min},{max} must satisfy {} <= min <= max <= {}",
            c.min, c.max
        )
    };
    let bad = [
        (
            Settings {
                view_angle_deg: 90.0,
                ..ok.clone()
            },
            format!("view angle 90 is outside {}", Settings::VIEW_ANGLE),
        ),
        (
            Settings {
                view_angle_deg: f32::NAN,
                ..ok.clone()
            },
            format!("view angle NaN is outside {}", Settings::VIEW_ANGLE),
        ),
        (
            Settings {
                depth_scale: -1.0,
                ..ok.clone()
            },
            format!("depth scale -1 is outside {}", Settings::DEPTH_SCALE),
        ),
        (
            Settings {
                depth_scale: f32::INFINITY,
                ..ok.clone()
            },
            format!("depth scale inf is outside {}", Settings::DEPTH_SCALE),
        ),
        (
            Settings {
                size: Size::new(0, 64),
                ..ok.clone()
            },
            format!("size 0x64 has a side outside {}", Settings::SIDE),
        ),
        (
            Settings {
                layers: Layers { min: 32, max: 8 },
                ..ok.clone()
            },
            layers(32, 8),
        ),
        (
            Settings {
                layers: Layers {
                    min: 1,
                    max: 1_000_000,
                },
                ..ok.clone()
            },
            layers(1, 1_000_000),
        ),
        (
            Settings {
                binary_steps: 1000,
                ..ok.clone()
            },
            format!("binary steps 1000 is outside {}", Settings::BINARY_STEPS),
        ),
    ];
    for (s, expected) in bad {
        assert_eq!(s.validate(), Err(expected), "{s:?}");
    }
    assert!("pyramid-bilinear".parse::<Method>().is_ok());
    assert!("pyramid2".parse::<Method>().unwrap_err().contains("pom"));
}

#[test]
fn float_exr_maps_load_as_stored() {
    let dir = std::env::temp_dir().join(format!("quadray-exr-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("ramp.exr");
    let img = image::Rgb32FImage::from_fn(8, 8, |x, y| {
        let v = (x + 8 * y) as f32 / 63.0;
        image::Rgb([v, v, v])
    });
    img.save(&path).unwrap();
    let map = HeightMap::load(&path, Convention::Depth, Fit::Exact).unwrap();
    assert_eq!((map.width, map.height), (8, 8));
    for (k, d) in map.depth.iter().enumerate() {
        assert!((d - k as f32 / 63.0).abs() < 1e-6, "texel {k}: {d}");
    }
}
