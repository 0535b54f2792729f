//! One knob, declared once: [`knobs!`] turns a family's declaration (field, default,
//! range or options with unit, doc) into its struct, its `Default` and its `Knob` table,
//! so that the name, the values text, the parser, the printer and the range test all come
//! from the one declaration.

use crate::error::clip;
use crate::quality::Quality;

/// One knob: what `specula knobs`, the README, the CLI, the C ABI and `Quality::set` see.
#[derive(Clone, Copy)]
pub struct Knob {
    pub name: &'static str,
    /// Accepted values with their unit, as `specula knobs` and the README show them.
    pub values: &'static str,
    pub default: &'static str,
    pub doc: &'static str,
    /// What `set` accepts, for the range test.
    pub range: Range,
    /// Parses a textual value into the knob's field; the error says what is accepted.
    pub set: fn(&mut Quality, &str) -> std::result::Result<(), String>,
    /// The field's value, as `set` accepts it.
    pub get: fn(&Quality) -> String,
}

/// The values a knob accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Whole numbers in lo..=hi.
    Count(u32, u32),
    /// Perfect squares in 1..=hi.
    Square(u32),
    /// Finite numbers in lo..=hi.
    Real(f32, f32),
    /// One of these names.
    Options(&'static [&'static str]),
    /// `auto` or whole numbers in lo..=hi.
    AutoCount(u32, u32),
    /// `auto` or a length > 0.
    AutoPositive,
    /// `auto` or x,y,z.
    AutoPoint,
}

/// A family of knobs that `Quality` composes: where its struct lives in a `Quality`.
pub trait Part {
    fn of(q: &Quality) -> &Self;
    fn of_mut(q: &mut Quality) -> &mut Self;
}

pub fn count(v: &str, lo: u32, hi: u32) -> std::result::Result<u32, String> {
    match v.trim().parse::<i64>() {
        Ok(n) if (lo as i64..=hi as i64).contains(&n) => Ok(n as u32),
        Ok(n) => Err(format!("{n} is outside {lo}..={hi}")),
        Err(_) => Err(format!("'{}' is not a whole number", clip(v))),
    }
}

pub fn square(v: &str, hi: u32, values: &str) -> std::result::Result<u32, String> {
    let n = count(v, 1, hi)?;
    if n.isqrt().pow(2) != n {
        return Err(format!("{n} is not a perfect square ({values})"));
    }
    Ok(n)
}

pub fn real(v: &str, lo: f32, hi: f32) -> std::result::Result<f32, String> {
    match v.trim().parse::<f32>() {
        Ok(x) if x.is_finite() && (lo..=hi).contains(&x) => Ok(x),
        Ok(x) if x.is_nan() => Err(format!("NaN is not a number in {lo}..={hi}")),
        Ok(x) => Err(format!("{x} is outside {lo}..={hi}")),
        Err(_) => Err(format!("'{}' is not a number (expected {lo}..={hi})", clip(v))),
    }
}

pub fn one_of<T: Copy>(v: &str, options: &[(&str, T)]) -> std::result::Result<T, String> {
    options.iter().find(|(n, _)| *n == v).map(|(_, t)| *t).ok_or_else(|| {
        let names: Vec<_> = options.iter().map(|(n, _)| *n).collect();
        format!("'{}' is not one of {}", clip(v), names.join(", "))
    })
}

pub fn name_of<T: PartialEq>(t: T, options: &[(&'static str, T)]) -> String {
    options.iter().find(|(_, o)| *o == t).map_or("?", |(n, _)| n).to_string()
}

pub fn auto_count(v: &str, lo: u32, hi: u32) -> std::result::Result<Option<u32>, String> {
    if v == "auto" {
        return Ok(None);
    }
    count(v, lo, hi).map(Some)
}

pub fn auto_positive(v: &str) -> std::result::Result<Option<f32>, String> {
    match v {
        "auto" => Ok(None),
        v => match v.trim().parse::<f32>() {
            Ok(r) if r > 0.0 && r.is_finite() => Ok(Some(r)),
            _ => Err(format!("'{}' is not auto or a radius > 0 in metres", clip(v))),
        },
    }
}

pub fn auto_point(v: &str) -> std::result::Result<Option<glam::Vec3>, String> {
    if v == "auto" {
        return Ok(None);
    }
    let parts: Vec<&str> = v.split(',').collect();
    let nums: Vec<f32> = parts.iter().filter_map(|s| s.trim().parse::<f32>().ok()).filter(|x| x.is_finite()).collect();
    if parts.len() != 3 || nums.len() != 3 {
        return Err(format!("'{}' is not auto or x,y,z with three finite numbers", clip(v)));
    }
    Ok(Some(glam::Vec3::new(nums[0], nums[1], nums[2])))
}

/// The option called `name` (a const fn: a default that names no option fails the build).
pub const fn pick<T: Copy>(name: &str, options: &[(&str, T)]) -> T {
    let mut i = 0;
    while i < options.len() {
        if options[i].0.len() == name.len() && same(options[i].0.as_bytes(), name.as_bytes()) {
            return options[i].1;
        }
        i += 1;
    }
    panic!("a knob's default names none of its options")
}

const fn same(a: &[u8], b: &[u8]) -> bool {
    let mut i = 0;
    while i < a.len() {
        if a[i] != b[i] {
            return false;
        }
        i += 1;
    }
    true
}

/// The upper bound of knob `name`'s count range (a const fn: for limits that follow it).
pub const fn count_hi(knobs: &[Knob], name: &str) -> u32 {
    let mut i = 0;
    while i < knobs.len() {
        if knobs[i].name.len() == name.len() && same(knobs[i].name.as_bytes(), name.as_bytes()) {
            if let Range::Count(_, hi) | Range::AutoCount(_, hi) = knobs[i].range {
                return hi;
            }
        }
        i += 1;
    }
    panic!("no count knob of that name")
}

/// The families' tables as one (a const fn, so that `KNOBS` stays a constant slice).
pub const fn concat<const N: usize>(parts: &[&[Knob]]) -> [Knob; N] {
    let mut out = [parts[0][0]; N];
    let (mut i, mut n) = (0, 0);
    while i < parts.len() {
        let mut j = 0;
        while j < parts[i].len() {
            out[n] = parts[i][j];
            n += 1;
            j += 1;
        }
        i += 1;
    }
    assert!(n == N, "N is the families' knob count");
    out
}

/// A doc comment's text without the leading space `///` leaves.
pub const fn doc(s: &'static str) -> &'static str {
    s.trim_ascii_start()
}

/// Declares a family's knobs: a struct with one field per knob, its `Default` (a const,
/// so that an option default that names no option fails the build), an associated const
/// per knob holding its name (`RaytraceKnobs::ray_budget`: methods list what they read
/// through these, the name is written nowhere else), `NAMES` and the `Knob` table. Each
/// knob is `doc field [as name]: Type = default, kind(args);` with kinds
/// `count(lo..=hi, "unit")`, `real(lo..=hi, "unit")`, `square(..=hi)`,
/// `one_of["name" => value, ...]` (or `one_of("unit")[...]`), `auto_count(lo..=hi)`,
/// `auto_metres()` and `auto_point("unit")`; `as name` gives a knob whose field reads better
/// under another name (`kd_restart as kd_traversal`).
macro_rules! knobs {
    (
        $(#[$meta:meta])*
        pub struct $S:ident {
            $(
                $(#[doc = $doc:literal])+
                $field:ident $(as $name:ident)? : $ty:ty = $def:tt, $kind:ident $args:tt $([$($opt:literal => $val:expr),+ $(,)?])? ;
            )*
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq, serde::Serialize)]
        pub struct $S {
            $( $(#[doc = $doc])+ pub $field: $ty, )*
        }

        #[allow(non_upper_case_globals)]
        impl $S {
            /// The documented defaults.
            pub const DEFAULT: Self = Self {
                $( $field: $crate::quality::knob::knob_kind!(default $kind $args $([$($opt => $val),+])?; $def), )*
            };
            $( $crate::quality::knob::knob_kind!(name_const $field $($name)?); )*
            /// The family's knob names, in declaration order.
            pub const NAMES: &'static [&'static str] = &[$( $crate::quality::knob::knob_kind!(name $field $($name)?) ),*];
            /// The family's knobs, in declaration order.
            pub const KNOBS: &'static [$crate::quality::knob::Knob] = &[$(
                $crate::quality::knob::Knob {
                    name: $crate::quality::knob::knob_kind!(name $field $($name)?),
                    values: $crate::quality::knob::knob_kind!(values $kind $args $([$($opt => $val),+])?),
                    default: $crate::quality::knob::knob_kind!(default_text $kind; $def),
                    doc: $crate::quality::knob::doc(concat!($($doc),+)),
                    range: $crate::quality::knob::knob_kind!(range $kind $args $([$($opt => $val),+])?),
                    set: |q, v| {
                        let x = $crate::quality::knob::knob_kind!(parse $kind $args $([$($opt => $val),+])?; v)?;
                        <$S as $crate::quality::knob::Part>::of_mut(q).$field = x;
                        Ok(())
                    },
                    get: |q| {
                        let x = &<$S as $crate::quality::knob::Part>::of(q).$field;
                        $crate::quality::knob::knob_kind!(print $kind $args $([$($opt => $val),+])?; x)
                    },
                }
            ),*];
        }

        impl Default for $S {
            fn default() -> Self {
                Self::DEFAULT
            }
        }
    };
}
pub(crate) use knobs;

/// The per-kind parts of [`knobs!`]: default value and text, values text, range, parser
/// and printer.
macro_rules! knob_kind {
    (name_const $field:ident) => { pub const $field: &'static str = stringify!($field); };
    (name_const $field:ident $name:ident) => { pub const $name: &'static str = stringify!($name); };
    (name $field:ident) => { stringify!($field) };
    (name $field:ident $name:ident) => { stringify!($name) };

    (default real $args:tt; $def:tt) => { $def as f32 };
    (default one_of $args:tt [$($opt:literal => $val:expr),+]; $def:tt) => { $crate::quality::knob::pick($def, &[$(($opt, $val)),+]) };
    (default $kind:ident $args:tt; auto) => { None };
    (default $kind:ident $args:tt; $def:tt) => { $def };
    (default_text one_of; $def:literal) => { $def };
    (default_text $kind:ident; $def:tt) => { stringify!($def) };

    (values square (..= $hi:literal)) => { concat!("1, 4, 9, ..., ", stringify!($hi)) };
    (values one_of ($($unit:literal)?) [$first:literal => $fv:expr $(, $opt:literal => $val:expr)*]) => {
        concat!($first $(, "|", $opt)* $(, " ", $unit)?)
    };
    (values auto_count ($lo:literal ..= $hi:literal)) => { concat!("auto|", stringify!($lo), "..=", stringify!($hi)) };
    // count and real
    (values $kind:ident ($lo:literal ..= $hi:literal $(, $unit:literal)?)) => {
        concat!(stringify!($lo), "..=", stringify!($hi) $(, " ", $unit)?)
    };
    (values auto_metres ()) => { "auto|metres" };
    (values auto_point ($unit:literal)) => { concat!("auto|x,y,z (", $unit, ")") };

    (range count ($lo:literal ..= $hi:literal $(, $unit:literal)?)) => { $crate::quality::knob::Range::Count($lo, $hi) };
    (range real ($lo:literal ..= $hi:literal $(, $unit:literal)?)) => { $crate::quality::knob::Range::Real($lo as f32, $hi as f32) };
    (range square (..= $hi:literal)) => { $crate::quality::knob::Range::Square($hi) };
    (range one_of $args:tt [$($opt:literal => $val:expr),+]) => { $crate::quality::knob::Range::Options(&[$($opt),+]) };
    (range auto_count ($lo:literal ..= $hi:literal)) => { $crate::quality::knob::Range::AutoCount($lo, $hi) };
    (range auto_metres ()) => { $crate::quality::knob::Range::AutoPositive };
    (range auto_point $args:tt) => { $crate::quality::knob::Range::AutoPoint };

    (parse count ($lo:literal ..= $hi:literal $(, $unit:literal)?); $v:ident) => { $crate::quality::knob::count($v, $lo, $hi) };
    (parse real ($lo:literal ..= $hi:literal $(, $unit:literal)?); $v:ident) => { $crate::quality::knob::real($v, $lo as f32, $hi as f32) };
    (parse square (..= $hi:literal); $v:ident) => {
        $crate::quality::knob::square($v, $hi, $crate::quality::knob::knob_kind!(values square (..= $hi)))
    };
    (parse one_of $args:tt [$($opt:literal => $val:expr),+]; $v:ident) => { $crate::quality::knob::one_of($v, &[$(($opt, $val)),+]) };
    (parse auto_count ($lo:literal ..= $hi:literal); $v:ident) => { $crate::quality::knob::auto_count($v, $lo, $hi) };
    (parse auto_metres (); $v:ident) => { $crate::quality::knob::auto_positive($v) };
    (parse auto_point $args:tt; $v:ident) => { $crate::quality::knob::auto_point($v) };

    (print one_of $args:tt [$($opt:literal => $val:expr),+]; $x:ident) => { $crate::quality::knob::name_of(*$x, &[$(($opt, $val)),+]) };
    (print auto_count $args:tt; $x:ident) => { $x.map_or("auto".into(), |l| l.to_string()) };
    (print auto_metres $args:tt; $x:ident) => { $x.map_or("auto".into(), |r| r.to_string()) };
    (print auto_point $args:tt; $x:ident) => { $x.map_or("auto".into(), |p| format!("{},{},{}", p.x, p.y, p.z)) };
    (print $kind:ident $args:tt; $x:ident) => { $x.to_string() };
}
pub(crate) use knob_kind;
