//! The engine-neutral tracing module, as the text a caller's shader includes.

/// `trace.wgsl`, the engine-neutral tracing module: `pyramid_trace`, `bilinear_trace` (the
/// bilinear refinement), `pyramid_lod`, `shadow_lit` / `pyramid_lit` (self-shadowing) and their
/// helpers, as WGSL functions taking the pyramid texture and plain parameters. Include it by
/// concatenation ahead of your own shader code (quadray's surface shader does); its header says
/// what a caller provides.
pub const TRACE_WGSL: &str = include_str!("trace.wgsl");
