//! Which cells and sub-cells a triangle overlaps: the separating-axis test of a triangle against
//! boxes ([`TriangleBoxTest`]) and the counting of a triangle in a cell's sub-cells
//! ([`count_subcells`]).

use super::{SUBCELLS, sub_bit, sub_cell};
use glam::{IVec3, Mat4, Vec3, Vec4};
use std::cell::OnceCell;

/// A triangle's separating-axis test against boxes (Akenine-Möller's: the box's axes, the
/// triangle's normal, and the nine cross products of their edges), its axes and the triangle's
/// extent along each found once for all the cells and sub-cells it is tested against. Lengths
/// are taken from its first vertex, so that rounding follows the box's distance from the
/// triangle, not the grid's coordinates.
pub(super) struct TriangleBoxTest {
    origin: Vec3,
    /// The triangle's vertices from `origin`, and their bounds.
    vertices: [Vec3; 3],
    lo: Vec3,
    hi: Vec3,
    /// The sub-cells of the triangle's bounds, first and last ([`SUBCELLS`] a grid unit).
    subcells: (IVec3, IVec3),
    /// The normal and the edges' nine axes; made only where a box needs them.
    axes: OnceCell<Axes>,
}

/// Axes of [`TriangleBoxTest`] four at a time, one a lane (the normal, then the edges'
/// crosses with x, y and z; a zero axis, which separates nothing, where an axis is shorter than
/// 1e-6 and in the last two lanes): their components, the components' magnitudes, and the
/// triangle's least and greatest projection on each. A box is tested against four axes at once,
/// each lane with the arithmetic of one axis's test, so that the answer is the one axis by axis.
struct Axes {
    x: [Vec4; AXIS_GROUPS],
    y: [Vec4; AXIS_GROUPS],
    z: [Vec4; AXIS_GROUPS],
    abs_x: [Vec4; AXIS_GROUPS],
    abs_y: [Vec4; AXIS_GROUPS],
    abs_z: [Vec4; AXIS_GROUPS],
    least: [Vec4; AXIS_GROUPS],
    most: [Vec4; AXIS_GROUPS],
}

/// Groups of four lanes the ten axes take.
const AXIS_GROUPS: usize = 3;

impl TriangleBoxTest {
    /// The test of triangle `t` (grid units).
    #[inline]
    pub(super) fn new(t: [Vec3; 3]) -> Self {
        let origin = t[0];
        let v = t.map(|p| p - origin);
        Self {
            origin,
            vertices: v,
            lo: v[0].min(v[1]).min(v[2]),
            hi: v[0].max(v[1]).max(v[2]),
            subcells: (
                floor(t[0].min(t[1]).min(t[2]) * SUBCELLS as f32),
                floor(t[0].max(t[1]).max(t[2]) * SUBCELLS as f32),
            ),
            axes: OnceCell::new(),
        }
    }

    /// The normal and the edges' nine axes, made at the first box the bounds do not decide.
    fn axes(&self) -> &Axes {
        self.axes.get_or_init(|| {
            let v = self.vertices;
            let edges = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
            let [c0, c1, c2] =
                edges.map(|e| [Vec3::X.cross(e), Vec3::Y.cross(e), Vec3::Z.cross(e)]);
            let groups = [
                [edges[0].cross(edges[1]), c0[0], c0[1], c0[2]],
                [c1[0], c1[1], c1[2], c2[0]],
                [c2[1], c2[2], Vec3::ZERO, Vec3::ZERO],
            ];
            let mut axes = Axes {
                x: [Vec4::ZERO; AXIS_GROUPS],
                y: [Vec4::ZERO; AXIS_GROUPS],
                z: [Vec4::ZERO; AXIS_GROUPS],
                abs_x: [Vec4::ZERO; AXIS_GROUPS],
                abs_y: [Vec4::ZERO; AXIS_GROUPS],
                abs_z: [Vec4::ZERO; AXIS_GROUPS],
                least: [Vec4::ZERO; AXIS_GROUPS],
                most: [Vec4::ZERO; AXIS_GROUPS],
            };
            for (g, group) in groups.into_iter().enumerate() {
                // (a transpose: the four axes' x, y and z)
                let [a, b, c, d] = group.map(|a| a.extend(0.0));
                let lanes = Mat4::from_cols(a, b, c, d).transpose();
                let (x, y, z) = (lanes.x_axis, lanes.y_axis, lanes.z_axis);
                let kept = (x * x + y * y + z * z).cmpge(Vec4::splat(1e-12));
                let p =
                    v.map(|v| Vec4::splat(v.x) * x + Vec4::splat(v.y) * y + Vec4::splat(v.z) * z);
                let keep = |a: Vec4| Vec4::select(kept, a, Vec4::ZERO);
                let (x, y, z) = (keep(x), keep(y), keep(z));
                axes.x[g] = x;
                axes.y[g] = y;
                axes.z[g] = z;
                axes.abs_x[g] = x.abs();
                axes.abs_y[g] = y.abs();
                axes.abs_z[g] = z.abs();
                axes.least[g] = keep(min_num(min_num(p[0], p[1]), p[2]));
                axes.most[g] = keep(max_num(max_num(p[0], p[1]), p[2]));
            }
            axes
        })
    }

    /// Whether the triangle overlaps the box of `centre` and `half` extents.
    pub(super) fn overlaps(&self, centre: Vec3, half: Vec3) -> bool {
        let d = centre - self.origin;
        // the box's axes: the triangle's bounds
        let (lo, hi) = (self.lo - d, self.hi - d);
        if lo.cmpgt(half).any() || hi.cmplt(-half).any() {
            return false;
        }
        // a triangle well inside the box overlaps it whatever the other axes say (most of a
        // small triangle's cells and sub-cells)
        let inner = half * (1.0 - 1e-5);
        if lo.cmpgt(-inner).all() && hi.cmplt(inner).all() {
            return true;
        }
        // the box's centre and extent along each axis, as a dot product adds them (x, y, z)
        let a = self.axes();
        let (dx, dy, dz) = (Vec4::splat(d.x), Vec4::splat(d.y), Vec4::splat(d.z));
        let (hx, hy, hz) = (
            Vec4::splat(half.x),
            Vec4::splat(half.y),
            Vec4::splat(half.z),
        );
        (0..AXIS_GROUPS).all(|g| {
            let c = dx * a.x[g] + dy * a.y[g] + dz * a.z[g];
            let r = hx * a.abs_x[g] + hy * a.abs_y[g] + hz * a.abs_z[g];
            !((a.least[g] - c).cmpgt(r) | (a.most[g] - c).cmplt(-r)).any()
        })
    }
}

/// Each lane's `f32::min`: the other where one is NaN.
fn min_num(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmplt(b) | b.is_nan_mask(), a, b)
}

/// Each lane's `f32::max`: the other where one is NaN.
fn max_num(a: Vec4, b: Vec4) -> Vec4 {
    Vec4::select(a.cmpgt(b) | b.is_nan_mask(), a, b)
}

/// `v.floor().as_ivec3()` without a call to `floorf` (which x86-64's baseline lacks an
/// instruction for): the truncation, one less where it rounded up; saturating alike.
pub(super) fn floor(v: Vec3) -> IVec3 {
    let floor = |x: f32| {
        let i = x as i32;
        if i as f32 > x { i.saturating_sub(1) } else { i }
    };
    IVec3::new(floor(v.x), floor(v.y), floor(v.z))
}

/// Counts the triangle of `test` in the sub-cells of cell `c` it overlaps, one each (at their
/// bits in the cell's masks).
pub(super) fn count_subcells(test: &TriangleBoxTest, c: IVec3, counts: &mut [u32]) {
    let k = SUBCELLS as f32;
    let first = c * SUBCELLS as i32;
    let lo = test.subcells.0.max(first);
    let hi = test.subcells.1.min(first + SUBCELLS as i32 - 1);
    for z in lo.z..=hi.z {
        for y in lo.y..=hi.y {
            for x in lo.x..=hi.x {
                let s = IVec3::new(x, y, z);
                // the cell's box's rule (a plane at a face in, one at the next out): the
                // sub-cells at the cell's faces end where the cell's box does
                let low = s.as_vec3() / k - Vec3::splat(1e-5);
                let high = (s + 1).as_vec3() / k - Vec3::splat(1e-4);
                if test.overlaps((low + high) * 0.5, (high - low) * 0.5) {
                    let (w, b) = sub_bit(sub_cell(s));
                    counts[w * 32 + b as usize] += 1;
                }
            }
        }
    }
}
