//! The direct light: each light view's shadow map, sized for the picture rather than the RSM
//! (the sun's fitted to what the camera sees, a spot's and a point light's faces the RSM's views;
//! [`shadow_map`]), and the pass that lights the G-buffer through them with a filtered
//! comparison ([`pass`]). The RSM's size decides only the bounce.

pub(crate) mod pass;
pub(crate) mod shadow_map;
