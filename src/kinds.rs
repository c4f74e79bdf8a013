//! The one declaration of a list of element kinds: joints, cut joints, force elements and
//! requirements are each one file per kind implementing the list's trait, and one `kinds!`
//! invocation that names them (after pinocchio's joint collection, whose variant dispatches to
//! each model's own implementation).
//!
//! The macro writes the enum `Kind`, its `ALL` (every kind, in the order listed to users),
//! `name()` (the kind's `NAME`, as written in the model file), and one method per line of
//! dispatch below the list, each forwarding to the kind's implementation: a constant
//! (`fn equations() -> usize = EQUATIONS;`), several constants as an array
//! (`fn uses() -> [Use; 3] = [AT, AXIS, AXIS2];`) or a function
//! (`fn values<T: Real>(g: &G<T>, out: &mut Vec<T>) = equations(g, out);`).
//!
//! Two shapes of list:
//! - `Variant => path::Type`: the kinds are types without data (a joint type): the enum is
//!   `Copy` with unit variants, its methods take `self`, functions are the trait's associated
//!   functions.
//! - `Variant(path::Type)`: each kind carries its settings (a requirement's bounds): the enum
//!   holds them, its methods take `&self`, functions are the trait's methods on the settings;
//!   the trait has a `NAME`, the `FIELDS` the kind takes (`NAMES` and `FIELDS` list them in
//!   order) and `fn read(fields) -> Result<Self, E>`, which `read(name, fields)` calls for the
//!   kind named `name`; a kind with no `FIELDS` serialises as its bare variant name.

/// See the [module documentation](self).
macro_rules! kinds {
    // Kinds without data.
    (
        $(#[$meta:meta])*
        pub enum $Kind:ident: $Trait:ident $list:tt
        $(
            $(#[$fmeta:meta])*
            fn $f:ident $(<$G:ident: $B:path>)? ($($a:ident: $t:ty),*) $(-> $r:ty)?
                = $how:tt $(($($arg:expr),*))?;
        )*
    ) => {
        $crate::kinds::kinds!(@unit_enum [$(#[$meta])*] $Kind, $Trait, $list);
        impl $Kind {
            $(
                $crate::kinds::kinds!(@unit $Kind, $Trait, $list,
                    [$(#[$fmeta])*] $f [$(<$G: $B>)?] ($($a: $t),*) [$(-> $r)?]
                    [$how $(($($arg),*))?]);
            )*
        }
    };
    // Kinds with their settings.
    (
        $(#[$meta:meta])*
        pub enum $Kind:ident: $Trait:ident $list:tt
        read($fields:ty) -> $Err:ty;
        $(
            $(#[$fmeta:meta])*
            fn $f:ident $(<$G:ident: $B:path>)? ($($a:ident: $t:ty),*) $(-> $r:ty)?
                = $how:tt $(($($arg:expr),*))?;
        )*
    ) => {
        $crate::kinds::kinds!(@data_enum [$(#[$meta])*] $Kind, $Trait, $list, $fields, $Err);
        impl $Kind {
            $(
                $crate::kinds::kinds!(@data $Kind, $Trait, $list,
                    [$(#[$fmeta])*] $f [$(<$G: $B>)?] ($($a: $t),*) [$(-> $r)?]
                    [$how $(($($arg),*))?]);
            )*
        }
    };
    (@unit_enum [$(#[$meta:meta])*] $Kind:ident, $Trait:ident,
        { $($variant:ident => $ty:path),* $(,)? }) => {
        $(#[$meta])*
        #[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
        pub enum $Kind {
            $($variant),*
        }

        impl $Kind {
            /// Every kind, in the order they are listed to users.
            pub const ALL: &[$Kind] = &[$($Kind::$variant),*];

            /// Name in the model file.
            pub fn name(self) -> &'static str {
                match self {
                    $($Kind::$variant => <$ty as $Trait>::NAME),*
                }
            }
        }
    };
    (@data_enum [$(#[$meta:meta])*] $Kind:ident, $Trait:ident,
        { $($variant:ident($ty:path)),* $(,)? }, $fields:ty, $Err:ty) => {
        $(#[$meta])*
        #[derive(Debug, Clone, PartialEq)]
        pub enum $Kind {
            $($variant($ty)),*
        }

        impl $Kind {
            /// The name of every kind, in the order they are listed to users.
            pub const NAMES: &[&str] = &[$(<$ty as $Trait>::NAME),*];

            /// The fields each kind takes, in the order of [`Self::NAMES`].
            pub const FIELDS: &[&[&str]] = &[$(<$ty as $Trait>::FIELDS),*];

            /// Name in the model file.
            pub fn name(&self) -> &'static str {
                match self {
                    $($Kind::$variant(_) => <$ty as $Trait>::NAME),*
                }
            }

            /// The kind named `name` read from `fields` (`None`: no kind has that name).
            pub fn read(name: &str, fields: $fields) -> Option<Result<$Kind, $Err>> {
                $(
                    if name == <$ty as $Trait>::NAME {
                        return Some(<$ty as $Trait>::read(fields).map($Kind::$variant));
                    }
                )*
                None
            }
        }

        impl serde::Serialize for $Kind {
            fn serialize<Z: serde::Serializer>(&self, z: Z) -> Result<Z::Ok, Z::Error> {
                let mut index = 0u32;
                $(
                    if let $Kind::$variant(x) = self {
                        return if <$ty as $Trait>::FIELDS.is_empty() {
                            z.serialize_unit_variant(stringify!($Kind), index, stringify!($variant))
                        } else {
                            z.serialize_newtype_variant(
                                stringify!($Kind), index, stringify!($variant), x,
                            )
                        };
                    }
                    index += 1;
                )*
                unreachable!("{index} kinds, each matched above")
            }
        }
    };
    // One method of kinds without data.
    (@unit $Kind:ident, $Trait:ident, { $($variant:ident => $ty:path),* $(,)? },
        [$(#[$fmeta:meta])*] $f:ident [$(<$G:ident: $B:path>)?] ($($a:ident: $t:ty),*)
        [$(-> $r:ty)?] $how:tt) => {
        $(#[$fmeta])*
        #[inline]
        pub fn $f $(<$G: $B>)? (self, $($a: $t),*) $(-> $r)? {
            match self {
                $($Kind::$variant => $crate::kinds::kinds!(@forward $ty, $Trait, $how)),*
            }
        }
    };
    // One method of kinds with their settings.
    (@data $Kind:ident, $Trait:ident, { $($variant:ident($ty:path)),* $(,)? },
        [$(#[$fmeta:meta])*] $f:ident [$(<$G:ident: $B:path>)?] ($($a:ident: $t:ty),*)
        [$(-> $r:ty)?] $how:tt) => {
        $(#[$fmeta])*
        #[inline]
        pub fn $f $(<$G: $B>)? (&self, $($a: $t),*) $(-> $r)? {
            match self {
                $($Kind::$variant(_x) => $crate::kinds::kinds!(@method _x, $ty, $Trait, $how)),*
            }
        }
    };
    // A type's constants as an array, its associated function, or one constant.
    (@forward $ty:path, $Trait:ident, [[$($C:ident),+]]) => {
        [$(<$ty as $Trait>::$C),+]
    };
    (@forward $ty:path, $Trait:ident, [$g:ident($($arg:expr),*)]) => {
        <$ty as $Trait>::$g($($arg),*)
    };
    (@forward $ty:path, $Trait:ident, [$C:ident]) => {
        <$ty as $Trait>::$C
    };
    // A method on a kind's settings, or its constant.
    (@method $x:ident, $ty:path, $Trait:ident, [$g:ident($($arg:expr),*)]) => {
        <$ty as $Trait>::$g($x, $($arg),*)
    };
    (@method $x:ident, $ty:path, $Trait:ident, [$C:ident]) => {
        <$ty as $Trait>::$C
    };
}

pub(crate) use kinds;
