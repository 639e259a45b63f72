//! The settings' rules: the levels' defaults, the resolved settings and each refusal's message
//! (the flags' round trip is beside the fields, in `settings.rs`, as a new field needs a value
//! there).

use super::*;

#[test]
fn default_levels_follow_the_rsm_and_given_ones_are_kept() {
    let c = ClusterSettings::DEFAULT;
    assert_eq!(c.levels(512), Levels { start: 6, limit: 3 });
    assert_eq!(c.levels(64), Levels { start: 3, limit: 0 });
    let given = ClusterSettings {
        start_level: Some(4),
        ..c
    };
    assert_eq!(given.levels(512), Levels { start: 4, limit: 3 });
}

#[test]
fn resolved_settings_render_the_same_and_write_every_default_out() {
    let s = Settings::sized(1920, 1080, 256);
    let r = s.resolved();
    // the shadow maps' default: twice the longer side, within 256-2048
    assert_eq!(r.shadow_map_size, Some(2048));
    assert_eq!(
        Settings::sized(100, 60, 64).shadow_map_size_or_default(),
        256
    );
    assert_eq!(
        Settings::sized(300, 500, 64).shadow_map_size_or_default(),
        1024
    );
    assert_eq!(
        (
            r.levels(),
            r.tile_error_or_default(),
            r.tile_capacity_or_default()
        ),
        (s.levels(), 0.002, 256)
    );
    assert!(r.cluster.start_level.is_some() && r.tile_capacity.is_some());
    // the one cut's shadow corners: the longer side over 120, each pixel walking where that is
    // no more than the interleave
    assert_eq!(r.shadow_corners, Some(16));
    let corners = |w, h, interleave| {
        Settings {
            interleave,
            ..Settings::sized(w, h, 64)
        }
        .shadow_corners_or_default()
    };
    assert_eq!(
        [
            corners(512, 512, 1),
            corners(256, 192, 1),
            corners(128, 128, 1),
            corners(480, 270, 4),
            corners(600, 400, 4),
        ],
        [4, 2, 0, 0, 5]
    );
}

/// Each refusal names the parameter and its declared range.
#[test]
fn validate_uses_the_declared_limits() {
    let ok = Settings::DEFAULT;
    assert!(ok.validate().is_ok());
    let top = ok.rsm_size.ilog2();
    let big = Size::new(8192, 8192);
    let bad = [
        (
            Settings {
                rsm_size: 96,
                ..ok.clone()
            },
            "RSM size 96 must be a power of two in",
            Settings::RSM_SIZE.to_string(),
        ),
        (
            Settings {
                shadow_map_size: Some(3000),
                ..ok.clone()
            },
            "shadow map size 3000 must be a power of two in",
            Settings::SHADOW_MAP_SIZE.to_string(),
        ),
        (
            Settings {
                size: Size::new(0, 4),
                ..ok.clone()
            },
            "size 0x4",
            Settings::SIDE.to_string(),
        ),
        (
            Settings {
                cluster: ClusterSettings {
                    limit_level: Some(7),
                    ..ClusterSettings::DEFAULT
                },
                ..ok.clone()
            },
            "levels must satisfy limit (7) <= start",
            format!("<= {top} (the 1x1 level of a {} RSM)", ok.rsm_size),
        ),
        (
            Settings {
                cluster: ClusterSettings {
                    normal_threshold: f32::NAN,
                    ..ClusterSettings::DEFAULT
                },
                ..ok.clone()
            },
            "normal threshold NaN",
            ClusterSettings::NORMAL_THRESHOLD.to_string(),
        ),
        (
            Settings {
                temporal_weight: 0.0,
                ..ok.clone()
            },
            "temporal weight 0",
            Settings::TEMPORAL_WEIGHT.to_string(),
        ),
        (
            Settings {
                tile_capacity: Some(2048),
                ..ok.clone()
            },
            "tile capacity 2048",
            Settings::TILE_CAPACITY.to_string(),
        ),
        (
            Settings {
                interleave: 3,
                ..ok.clone()
            },
            "interleave 3 must be a power of two",
            "(its parts are classes of the cut's 4x4)".to_string(),
        ),
        (
            Settings {
                interleave: 4,
                subsample: 2,
                ..ok.clone()
            },
            "interleave 4 and subsample 2 cannot both be above 1",
            "rejoins full-resolution pixels".to_string(),
        ),
        (
            Settings {
                shadow_grid_levels: 3,
                ..ok.clone()
            },
            "shadow grid levels 3",
            Settings::SHADOW_GRID_LEVELS.to_string(),
        ),
        (
            Settings {
                shadow_grid: 256,
                shadow_grid_levels: 2,
                ..ok.clone()
            },
            "shadow grid 256 with 2 levels must be at most 128 cells",
            "(its sub-cells take two words a set cell)".to_string(),
        ),
        (
            Settings {
                size: big,
                tile_capacity: Some(1024),
                ..ok.clone()
            },
            "per-tile cuts of 1024 nodes",
            format!(
                "lower the tile capacity to {} or less",
                Settings::tile_capacity_within(big, Settings::MAX_TILE_LIST_BYTES)
            ),
        ),
    ];
    for (s, what, range) in bad {
        let e = s.validate().unwrap_err();
        assert!(e.starts_with(what) && e.ends_with(&range), "{e}");
    }
}
