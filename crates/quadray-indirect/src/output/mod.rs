//! What follows the gather: the geometry-aware upsampling of the sub-sampled methods
//! ([`upsample`]), the temporal filter ([`temporal`]) and the output pass into the caller's
//! texture ([`pass`]).

pub(crate) mod pass;
pub(crate) mod temporal;
pub(crate) mod upsample;
