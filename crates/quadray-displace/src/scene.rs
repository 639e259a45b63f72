//! Surfaces the height field is mapped onto, and the camera and light for a view angle.

use glam::{Mat4, Vec3};

/// What the map is displacing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum SurfaceKind {
    /// A large quad with the map tiled 8 x 8 (surface detail: rays wrap).
    Wall,
    /// One copy of the map; rays that leave it are discarded (terrain, height mapping).
    Terrain,
    /// A depth photograph with its colour image, seen from a new viewpoint (figure 1e).
    Photo,
}

impl SurfaceKind {
    pub fn tiles(self) -> u32 {
        match self {
            SurfaceKind::Wall => 8,
            SurfaceKind::Terrain | SurfaceKind::Photo => 1,
        }
    }

    pub fn wraps(self) -> bool {
        self == SurfaceKind::Wall
    }

    /// Camera distance from the surface centre, in tiles.
    fn distance(self) -> f32 {
        match self {
            SurfaceKind::Wall => 1.6,
            SurfaceKind::Terrain | SurfaceKind::Photo => 1.35,
        }
    }
}

impl std::str::FromStr for SurfaceKind {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "wall" => Ok(SurfaceKind::Wall),
            "terrain" => Ok(SurfaceKind::Terrain),
            "photo" => Ok(SurfaceKind::Photo),
            _ => Err(format!(
                "unknown surface `{s}` (one of: wall, terrain, photo)"
            )),
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    /// xyz: world direction of +u; w: sign such that +v = w * (N x T).
    pub tangent: [f32; 4],
    pub uv: [f32; 2],
}

/// The plane every surface lies in: y = 0, +u along +x, +v along +z, normal +y; one tile is one
/// world unit.
pub struct Plane {
    pub origin: Vec3,
    pub u: Vec3,
    pub v: Vec3,
}

impl Plane {
    pub fn of(kind: SurfaceKind) -> Self {
        let extent = kind.tiles() as f32;
        Self {
            origin: Vec3::new(-extent / 2.0, 0.0, -extent / 2.0),
            u: Vec3::X,
            v: Vec3::Z,
        }
    }

    pub fn normal(&self) -> Vec3 {
        self.v.cross(self.u).normalize()
    }

    /// Two triangles spanning the surface, uv running 0..tiles.
    pub fn quad(&self, tiles: u32) -> [Vertex; 6] {
        let t = tiles as f32;
        let n = self.normal();
        // +v = w * (N x T): here N x T = y x x = -z while +v is +z.
        let w = if n.cross(self.u).dot(self.v) > 0.0 {
            1.0
        } else {
            -1.0
        };
        let corner = |a: f32, b: f32| Vertex {
            position: (self.origin + self.u * a * t + self.v * b * t).to_array(),
            normal: n.to_array(),
            tangent: [self.u.x, self.u.y, self.u.z, w],
            uv: [a * t, b * t],
        };
        [
            corner(0.0, 0.0),
            corner(1.0, 0.0),
            corner(0.0, 1.0),
            corner(0.0, 1.0),
            corner(1.0, 0.0),
            corner(1.0, 1.0),
        ]
    }
}

/// Camera and light for a view angle (degrees between the view direction at the surface centre
/// and the surface normal). The camera looks 30 degrees off the v axis so both DDA axes work.
pub struct View {
    pub view_proj: Mat4,
    pub eye: Vec3,
    pub light: Vec3,
}

impl View {
    pub fn new(kind: SurfaceKind, view_angle_deg: f32, width: u32, height: u32) -> Self {
        let plane = Plane::of(kind);
        let tiles = kind.tiles() as f32;
        let centre = plane.origin + (plane.u + plane.v) * tiles / 2.0;
        let n = plane.normal();
        let azimuth = 30f32.to_radians();
        let away = -(plane.v * azimuth.cos() + plane.u * azimuth.sin());
        let right = plane.u * azimuth.cos() - plane.v * azimuth.sin();
        let theta = view_angle_deg.to_radians();
        let eye = centre + (n * theta.cos() + away * theta.sin()) * kind.distance();
        let forward = (centre - eye).normalize();
        let up = forward.cross(right);
        let view = glam::camera::rh::view::look_at_mat4(eye, centre, up);
        let proj = glam::camera::rh::proj::directx::perspective(
            50f32.to_radians(),
            width as f32 / height as f32,
            0.01,
            100.0,
        );
        // A light to the side and above, low enough to cast visible self-shadows.
        let light = centre + n * 1.2 + right * 1.6 - away * 0.4;
        Self {
            view_proj: proj * view,
            eye,
            light,
        }
    }
}
