//! The per-tile cuts' deblocking filter ([`crate::Settings::tile_deblock`]), the CPU's twin of
//! the shader's (`deblock.wgsl`). Neighbouring tiles' cuts differ, so their light
//! steps at the boundary between them where the truth is smooth. On each line of pixels across
//! a boundary, the step between the two pixels beside it that the slopes on either side do not
//! explain is spread as a ramp over `radius` pixels each side, where those pixels and one more
//! each side lie on one surface: a video codec's deblocking filter, with the G-buffer for its
//! edges. It works on the irradiance (the radiance over the albedo), so that textures keep their
//! detail; the boundaries across columns first, then across rows.

use crate::frame::{NORMAL_AGREEMENT, Receiver};
use crate::settings::TILE;

/// An unexplained step larger than the light beside it is the light's own edge: kept (the
/// shader's `DEBLOCK_LIMIT`, in its prelude).
pub(crate) const LIMIT: f32 = 1.0;
/// Two neighbours lie on one surface where their normals agree ([`NORMAL_AGREEMENT`]) and the
/// step between them leaves their plane by at most this sine (a silhouette's steps along the
/// view ray; `DEBLOCK_PLANE`).
pub(crate) const PLANE: f32 = 0.2;
/// Albedo below this leaves a channel's light as it is (no irradiance to recover;
/// `DEBLOCK_ALBEDO`).
pub(crate) const ALBEDO: f32 = 1e-4;

/// Filters `radiance` (a `width`-wide picture's indirect light, rows top down) over
/// `receivers` (its G-buffer: `None` where it sees no geometry) with `radius` pixels each side
/// of a boundary (at most `TILE / 2 - 1`; 0 leaves it as it is).
///
/// # Panics
/// Where `receivers` is not `radiance`'s size or `radius` is over `TILE / 2 - 1`.
pub fn deblock(
    radiance: &mut [[f32; 3]],
    receivers: &[Option<Receiver>],
    width: usize,
    radius: usize,
) {
    assert_eq!(radiance.len(), receivers.len(), "a receiver a pixel");
    assert!(radius < TILE as usize / 2, "deblocking radius {radius}");
    if radius == 0 || width == 0 {
        return;
    }
    let height = radiance.len() / width;
    let tile = TILE as usize;
    for axis in 0..2 {
        let (lines, along) = if axis == 0 {
            (height, width)
        } else {
            (width, height)
        };
        let at = |line: usize, i: usize| {
            if axis == 0 {
                line * width + i
            } else {
                i * width + line
            }
        };
        for line in 0..lines {
            for start in (tile..).step_by(tile).take_while(|&s| s + radius < along) {
                let window: Vec<usize> = (start - radius - 1..=start + radius)
                    .map(|i| at(line, i))
                    .collect();
                filter_window(radiance, receivers, &window, radius);
            }
        }
    }
}

/// One boundary's window: `radius` + 1 pixels each side, the boundary's first pixel at
/// `radius` + 1.
fn filter_window(
    radiance: &mut [[f32; 3]],
    receivers: &[Option<Receiver>],
    window: &[usize],
    radius: usize,
) {
    let surfaces: Option<Vec<&Receiver>> = window.iter().map(|&p| receivers[p].as_ref()).collect();
    let Some(surfaces) = surfaces else {
        return;
    };
    if !surfaces
        .windows(2)
        .all(|pair| one_surface(pair[0], pair[1]))
    {
        return;
    }
    let k = radius + 1;
    let albedo = |i: usize| surfaces[i].albedo;
    let mut irradiance: Vec<[f32; 3]> = (0..window.len())
        .map(|i| {
            let e = radiance[window[i]];
            std::array::from_fn(|c| {
                if albedo(i)[c] > ALBEDO {
                    e[c] / albedo(i)[c]
                } else {
                    0.0
                }
            })
        })
        .collect();
    let spread: [f32; 3] = std::array::from_fn(|c| {
        let e = |i: usize| irradiance[i][c];
        let step = e(k) - e(k - 1);
        let slope = 0.5 * (e(k - 1) - e(k - 2) + e(k + 1) - e(k));
        let excess = step - slope;
        let level = 0.5 * (e(k).abs() + e(k - 1).abs());
        if excess.abs() <= LIMIT * level {
            excess
        } else {
            0.0
        }
    });
    for j in 0..radius {
        let w = (radius - j) as f32 / (2 * radius) as f32;
        for (value, s) in irradiance[k - 1 - j].iter_mut().zip(spread) {
            *value += w * s;
        }
        for (value, s) in irradiance[k + j].iter_mut().zip(spread) {
            *value -= w * s;
        }
    }
    for i in 1..=2 * radius {
        let e = &mut radiance[window[i]];
        *e = std::array::from_fn(|c| {
            if albedo(i)[c] > ALBEDO {
                irradiance[i][c] * albedo(i)[c]
            } else {
                e[c]
            }
        });
    }
}

/// Whether neighbours `a` and `b` lie on one surface.
fn one_surface(a: &Receiver, b: &Receiver) -> bool {
    let d: [f32; 3] = std::array::from_fn(|i| b.position[i] - a.position[i]);
    let dot = |u: &[f32; 3], v: &[f32; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    dot(&a.normal, &b.normal) > NORMAL_AGREEMENT
        && dot(&d, &a.normal).abs() <= PLANE * dot(&d, &d).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    const W: usize = 32;
    const H: usize = 16;

    /// A floor seen from above: every pixel on the plane z = 0, a unit apart, albedo `albedo`.
    fn floor(albedo: f32) -> Vec<Option<Receiver>> {
        (0..W * H)
            .map(|p| {
                Some(Receiver {
                    position: [(p % W) as f32, (p / W) as f32, 0.0],
                    normal: [0.0, 0.0, 1.0],
                    albedo: [albedo; 3],
                })
            })
            .collect()
    }

    /// Light that rises along x (`slope` a pixel) and steps up by `step` at each tile boundary.
    fn stepped(slope: f32, step: f32) -> Vec<[f32; 3]> {
        (0..W * H)
            .map(|p| {
                let x = p % W;
                [1.0 + slope * x as f32 + step * (x / TILE as usize) as f32; 3]
            })
            .collect()
    }

    /// The largest step between neighbours along x at the boundaries, and elsewhere.
    fn steps(radiance: &[[f32; 3]]) -> (f32, f32) {
        let (mut across, mut elsewhere) = (0.0f32, 0.0f32);
        for y in 0..H {
            for x in 1..W {
                let d = (radiance[y * W + x][0] - radiance[y * W + x - 1][0]).abs();
                if x % TILE as usize == 0 {
                    across = across.max(d);
                } else {
                    elsewhere = elsewhere.max(d);
                }
            }
        }
        (across, elsewhere)
    }

    #[test]
    fn a_step_at_each_boundary_becomes_a_ramp() {
        let receivers = floor(0.5);
        let mut radiance = stepped(0.01, 0.2);
        deblock(&mut radiance, &receivers, W, 3);
        let (across, elsewhere) = steps(&radiance);
        // the step of 0.2 spread over six steps (a third each side, in halves), on the slope
        assert!((across - 0.01).abs() < 1e-5, "across {across}");
        assert!(elsewhere < 0.01 + 0.2 / 3.0 + 1e-5, "elsewhere {elsewhere}");
        // the light's sum over a line is kept
        let sum = |r: &[[f32; 3]]| r[..W].iter().map(|p| p[0]).sum::<f32>();
        assert!((sum(&radiance) - sum(&stepped(0.01, 0.2))).abs() < 1e-4);
    }

    #[test]
    fn smooth_light_is_left_as_it_is() {
        let receivers = floor(0.7);
        let mut radiance = stepped(0.03, 0.0);
        let before = radiance.clone();
        deblock(&mut radiance, &receivers, W, 3);
        for (a, b) in radiance.iter().zip(&before) {
            assert!((a[0] - b[0]).abs() < 1e-5, "{} -> {}", b[0], a[0]);
        }
    }

    #[test]
    fn geometric_edges_and_the_light_s_own_edges_are_kept() {
        let mut radiance = stepped(0.0, 0.2);
        let before = radiance.clone();
        // a silhouette two pixels left of every boundary: the right side a unit nearer the eye
        let mut receivers = floor(0.5);
        for (p, r) in receivers.iter_mut().enumerate() {
            let r = r.as_mut().unwrap();
            if (p % W + 2) % TILE as usize >= 6 {
                r.position[2] = 1.0;
            }
        }
        deblock(&mut radiance, &receivers, W, 3);
        assert_eq!(radiance, before);
        // a step larger than the light beside it
        let mut radiance: Vec<[f32; 3]> = (0..W * H)
            .map(|p| {
                [if (p % W / TILE as usize).is_multiple_of(2) {
                    1.0
                } else {
                    5.0
                }; 3]
            })
            .collect();
        let before = radiance.clone();
        deblock(&mut radiance, &floor(0.5), W, 3);
        assert_eq!(radiance, before);
    }

    #[test]
    fn radius_zero_and_black_albedo_change_nothing() {
        let mut radiance = stepped(0.01, 0.2);
        let before = radiance.clone();
        deblock(&mut radiance, &floor(0.5), W, 0);
        deblock(&mut radiance, &floor(0.0), W, 3);
        assert_eq!(radiance, before);
    }
}
