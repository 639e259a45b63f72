//! Structs shared with WGSL, each declared once in Rust: [`shader_struct!`] makes the
//! `#[repr(C)]`, `Pod` struct and its WGSL declaration from one list of fields, and the WGSL
//! prelude (`contract.rs`) puts every declaration in front of every shader. A test parses them with
//! naga and holds each struct's WGSL layout (size, field offsets) to the Rust one, so that a field
//! whose WGSL alignment differs from Rust's fails there, not in a picture.

/// A Rust field type's WGSL spelling.
pub(crate) trait WgslType {
    /// The type as WGSL writes it.
    const WGSL: &'static str;
}

macro_rules! wgsl_types {
    ($($rust:ty => $wgsl:literal),* $(,)?) => {
        $(impl WgslType for $rust {
            const WGSL: &'static str = $wgsl;
        })*
    };
}

wgsl_types! {
    u32 => "u32",
    f32 => "f32",
    [u32; 2] => "vec2<u32>",
    [u32; 4] => "vec4<u32>",
    [f32; 4] => "vec4<f32>",
    [[f32; 4]; 4] => "mat4x4<f32>",
}

/// A struct shared with WGSL, declared by [`shader_struct!`].
pub(crate) trait ShaderStruct: bytemuck::Pod {
    /// Its WGSL name.
    const NAME: &'static str;

    /// Its fields in order: name, WGSL type, byte offset in the Rust struct.
    fn fields() -> Vec<(&'static str, &'static str, usize)>;

    /// Its WGSL declaration.
    fn wgsl() -> String {
        let fields: String = Self::fields()
            .into_iter()
            .map(|(name, ty, _)| format!("    {name}: {ty},\n"))
            .collect();
        format!("struct {} {{\n{fields}}}\n", Self::NAME)
    }
}

/// A shared struct's WGSL declaration (for the prelude) and, for the contract test, which
/// compares it with naga's, its Rust layout.
pub(crate) struct Layout {
    /// The WGSL declaration.
    pub wgsl: String,
    /// The WGSL name.
    #[cfg(test)]
    pub name: &'static str,
    /// Bytes of the Rust struct.
    #[cfg(test)]
    pub size: usize,
    /// Field names and Rust byte offsets, in order.
    #[cfg(test)]
    pub offsets: Vec<(&'static str, usize)>,
}

impl Layout {
    /// The layout of `T`.
    pub fn of<T: ShaderStruct>() -> Self {
        Self {
            wgsl: T::wgsl(),
            #[cfg(test)]
            name: T::NAME,
            #[cfg(test)]
            size: size_of::<T>(),
            #[cfg(test)]
            offsets: T::fields().into_iter().map(|(n, _, o)| (n, o)).collect(),
        }
    }
}

/// Declares a struct shared with WGSL: `struct Rust as "Wgsl" { field: type, ... }` makes the
/// `#[repr(C)]`, `Pod` Rust struct (its fields public to the crate) and its [`ShaderStruct`]
/// impl, whose `wgsl()` is the WGSL declaration. With `(arg: Type)` after the WGSL name and
/// `= value` after each field's type, it also makes `fn new(arg: Type) -> Self` filling each
/// field from its value, so that a field is one line.
macro_rules! shader_struct {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident as $wgsl:literal {
            $($(#[$field_meta:meta])* $field:ident: $ty:ty),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[repr(C)]
        #[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
        $vis struct $name {
            $($(#[$field_meta])* pub $field: $ty,)*
        }

        impl $crate::shader_struct::ShaderStruct for $name {
            const NAME: &'static str = $wgsl;

            fn fields() -> Vec<(&'static str, &'static str, usize)> {
                vec![$((
                    stringify!($field),
                    <$ty as $crate::shader_struct::WgslType>::WGSL,
                    std::mem::offset_of!($name, $field),
                )),*]
            }
        }
    };
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident as $wgsl:literal ($arg:ident: $arg_ty:ty) {
            $($(#[$field_meta:meta])* $field:ident: $ty:ty = $value:expr),* $(,)?
        }
    ) => {
        $crate::shader_struct::shader_struct! {
            $(#[$meta])*
            $vis struct $name as $wgsl {
                $($(#[$field_meta])* $field: $ty),*
            }
        }

        impl $name {
            /// The struct's values.
            pub(crate) fn new($arg: $arg_ty) -> Self {
                Self { $($field: $value),* }
            }
        }
    };
}

pub(crate) use shader_struct;
