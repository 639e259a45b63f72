//! The one set of displacement parameters the library, `quadray displace` and the viewer share,
//! with the command-line flags that spell them.

use crate::method::Method;
use std::fmt;
use std::str::FromStr;

/// Finest level the traversal may reach.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Lod {
    /// From screen-space derivatives of the texture coordinate, as mip selection does (3.4).
    Auto,
    /// A fixed level (0: the map's own texels).
    Level(u32),
}

impl fmt::Display for Lod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Lod::Auto => f.write_str("auto"),
            Lod::Level(l) => write!(f, "{l}"),
        }
    }
}

impl FromStr for Lod {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Lod::Auto),
            n => n
                .parse()
                .map(Lod::Level)
                .map_err(|_| format!("`{s}` is not `auto` or a level")),
        }
    }
}

/// Everything a frame depends on besides the map and the surface.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Settings {
    /// The search (or the mesh baseline).
    pub method: Method,
    /// Angle between the view direction at the surface centre and the normal, degrees (0..89).
    pub view_angle_deg: f32,
    /// Frame width in pixels.
    pub width: u32,
    /// Frame height in pixels.
    pub height: u32,
    /// Texture units per unit of depth (Bevy's default 0.1).
    pub depth_scale: f32,
    /// POM / relief layer counts, from head-on (min) to grazing (max); cone stepping takes the
    /// max as its number of cone steps.
    pub layers: (u32, u32),
    /// Relief mapping's and cone stepping's binary search steps.
    pub binary_steps: u32,
    /// Finest pyramid level the traversal reaches.
    pub lod: Lod,
    /// Self-shadowing by tracing from the light.
    pub shadows: bool,
    /// Camera azimuth around the surface normal (degrees): the benchmark keeps the default; the
    /// viewer moves it.
    pub azimuth_deg: f32,
    /// Camera distance as a multiple of the surface's default.
    pub zoom: f32,
    /// The light's azimuth around the surface normal, degrees.
    pub light_azimuth_deg: f32,
    /// Colour each pixel by the iterations its search took (0..64, black to white).
    pub show_iterations: bool,
}

impl Default for Settings {
    fn default() -> Self {
        Self {
            method: Method::Pyramid,
            view_angle_deg: 45.0,
            width: 512,
            height: 512,
            depth_scale: 0.1,
            layers: (8, 32),
            binary_steps: 5,
            lod: Lod::Level(0),
            shadows: false,
            azimuth_deg: 30.0,
            zoom: 1.0,
            light_azimuth_deg: 30.0,
            show_iterations: false,
        }
    }
}

impl Settings {
    /// POM as Bevy ships it: 16 layers at grazing angles down to 1 head-on, depth scale 0.1.
    pub fn bevy_pom() -> Self {
        Self {
            method: Method::Pom,
            layers: (1, 16),
            ..Default::default()
        }
    }

    /// Relief mapping as three.js's example ships it: 20..25 layers and 5 binary steps.
    pub fn threejs_relief() -> Self {
        Self {
            method: Method::Relief,
            layers: (20, 25),
            binary_steps: 5,
            ..Default::default()
        }
    }

    /// Relaxed cone step mapping with 15 cone steps and 8 binary steps: a fixed budget in the
    /// range the chapter's shaders use.
    pub fn relaxed_cone() -> Self {
        Self {
            method: Method::Cone,
            layers: (15, 15),
            binary_steps: 8,
            ..Default::default()
        }
    }

    /// Refuses parameters that would make no picture or an absurd amount of work.
    pub fn validate(&self) -> Result<(), String> {
        let s = self;
        if !(s.view_angle_deg.is_finite() && (0.0..=89.0).contains(&s.view_angle_deg)) {
            return Err(format!(
                "view angle {} is outside 0..89 degrees",
                s.view_angle_deg
            ));
        }
        if !(1..=8192).contains(&s.width) || !(1..=8192).contains(&s.height) {
            return Err(format!(
                "size {}x{} is outside 1x1..8192x8192",
                s.width, s.height
            ));
        }
        if !(s.depth_scale.is_finite() && s.depth_scale > 0.0 && s.depth_scale <= 10.0) {
            return Err(format!("depth scale {} is outside (0, 10]", s.depth_scale));
        }
        if s.layers.0 < 1 || s.layers.0 > s.layers.1 || s.layers.1 > 4096 {
            return Err(format!(
                "layers {},{} must satisfy 1 <= min <= max <= 4096",
                s.layers.0, s.layers.1
            ));
        }
        if !(s.azimuth_deg.is_finite() && s.light_azimuth_deg.is_finite()) {
            return Err("azimuths must be finite".into());
        }
        if !(s.zoom.is_finite() && (0.05..=20.0).contains(&s.zoom)) {
            return Err(format!("zoom {} is outside 0.05..20", s.zoom));
        }
        if s.binary_steps > 64 {
            return Err(format!("{} binary steps is more than 64", s.binary_steps));
        }
        Ok(())
    }

    /// The `quadray displace` flags that render these settings (the viewer prints them beside its
    /// screenshots; the CLI's tests parse them back).
    pub fn to_args(&self) -> Vec<String> {
        let mut args: Vec<String> = [
            ("--method", self.method.to_string()),
            ("--view-angle", self.view_angle_deg.to_string()),
            ("--azimuth", self.azimuth_deg.to_string()),
            ("--zoom", self.zoom.to_string()),
            ("--light-azimuth", self.light_azimuth_deg.to_string()),
            ("--size", format!("{}x{}", self.width, self.height)),
            ("--depth-scale", self.depth_scale.to_string()),
            ("--layers", format!("{},{}", self.layers.0, self.layers.1)),
            ("--binary-steps", self.binary_steps.to_string()),
            ("--lod", self.lod.to_string()),
        ]
        .into_iter()
        .flat_map(|(flag, value)| [flag.to_string(), value])
        .collect();
        for (on, flag) in [
            (self.shadows, "--shadows"),
            (self.show_iterations, "--show-iterations"),
        ] {
            if on {
                args.push(flag.into());
            }
        }
        args
    }
}
