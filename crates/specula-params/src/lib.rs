//! Parameters and options, each declared once.
//!
//! A technique declares its parameters in one [`params!`](crate::params) block: per parameter
//! the field it sets, its type, and a [`Param`] (kind and range, default, one line of doc, what a
//! change redoes). From that block come the [`ParamSpec`] list (`specula methods`, reports, the
//! viewer's controls, `-p` parsing), the defaults, reading and setting by name ([`ParamSet`]),
//! and the parameter table of the technique's module doc ([`doc_table`], kept current by a
//! test). An analysis declares its options the same way, in an [`options!`](crate::options)
//! block (with units and groups; see [`OptionSpec`]). This crate depends on no GPU, so that
//! specula-analyze and specula-core can both use it.
//!
//! ```
//! use specula_params::{params, Invalidates, Param, ParamKind, ParamSet, ParamValue};
//!
//! params! {
//!     /// A toy technique's parameters.
//!     pub struct ToyParams {
//!         samples: u32 = Param {
//!             kind: ParamKind::Integer { min: 1, max: 64 },
//!             default: "4",
//!             doc: "samples per pixel",
//!             invalidates: Invalidates::Uniform,
//!         },
//!     }
//! }
//! let mut p = ToyParams::default();
//! assert_eq!(p.samples, 4);
//! assert_eq!(ToyParams::SPECS[0].name, "samples");
//! p.set("samples", &ParamValue::Integer(8)).unwrap().unwrap();
//! assert_eq!(p.get("samples").as_deref(), Some("8"));
//! ```

use std::fmt;

mod options;
pub use options::{apply_option, option_default, options_table, Opt, OptionSpec};

/// A value its parameter or option refuses: who owns it (a technique or an analysis), the
/// parameter's name, the value and why.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("{owner}: {name} = {value:?}: {reason}")]
pub struct ParamError {
    pub owner: &'static str,
    pub name: String,
    pub value: String,
    pub reason: String,
}

/// What a parameter's value may be.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ParamKind {
    /// A whole number in `min..=max`.
    Integer { min: i64, max: i64 },
    /// A number in `min..=max`.
    Number { min: f64, max: f64 },
    /// `true` or `false`.
    Flag,
    /// One of these words.
    Choice(&'static [&'static str]),
    /// Free text the technique parses itself; `expected` says what it takes.
    Text { expected: &'static str },
    /// Finite numbers given together, comma-separated; `names` says which (`X,Y,Z`).
    Numbers { names: &'static str },
}

/// What changing a parameter makes stale.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Invalidates {
    /// Nothing but a value read each frame (a uniform, a loop bound).
    Uniform,
    /// The technique's own GPU resources (maps, pipelines); the scene preparation is kept.
    Resources,
    /// Everything the technique prepared for the scene.
    Scene,
}

impl Invalidates {
    pub fn describe(self) -> &'static str {
        match self {
            Invalidates::Uniform => "uniform",
            Invalidates::Resources => "resources",
            Invalidates::Scene => "scene preparation",
        }
    }
}

/// One parameter of a technique: the single source of its parsing, listing, reports and UI.
#[derive(Clone, Copy, Debug)]
pub struct ParamSpec {
    pub name: &'static str,
    pub kind: ParamKind,
    pub default: &'static str,
    pub doc: &'static str,
    pub invalidates: Invalidates,
}

/// A parsed parameter value.
#[derive(Clone, Debug, PartialEq)]
pub enum ParamValue {
    Integer(i64),
    Number(f64),
    Flag(bool),
    Word(String),
    /// Numbers given together (a point X,Y,Z; a box W,H,NX,NY).
    Numbers(Vec<f64>),
    /// A repeatable option's values, in the order given.
    List(Vec<ParamValue>),
    /// An option left out that has no default: the analysis's own rule decides.
    Unset,
}

impl fmt::Display for ParamValue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ParamValue::Integer(v) => write!(f, "{v}"),
            ParamValue::Number(v) => write!(f, "{v}"),
            ParamValue::Flag(v) => write!(f, "{v}"),
            ParamValue::Word(v) => write!(f, "{v}"),
            ParamValue::Numbers(v) => {
                let texts: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                write!(f, "{}", texts.join(","))
            }
            ParamValue::List(v) => {
                let texts: Vec<String> = v.iter().map(|x| x.to_string()).collect();
                write!(f, "{}", texts.join(";"))
            }
            ParamValue::Unset => Ok(()),
        }
    }
}

impl ParamValue {
    /// The value as a whole number (integers only; the spec's range has been checked).
    pub fn integer(&self) -> i64 {
        match self {
            ParamValue::Integer(v) => *v,
            ParamValue::Number(v) => *v as i64,
            _ => 0,
        }
    }

    pub fn number(&self) -> f64 {
        match self {
            ParamValue::Integer(v) => *v as f64,
            ParamValue::Number(v) => *v,
            _ => 0.0,
        }
    }

    pub fn flag(&self) -> bool {
        matches!(self, ParamValue::Flag(true))
    }

    pub fn word(&self) -> &str {
        match self {
            ParamValue::Word(w) => w,
            _ => "",
        }
    }
}

impl ParamKind {
    /// What a value must be, for error messages and listings.
    pub fn describe(&self) -> String {
        match self {
            ParamKind::Integer { min, max } => format!("a whole number from {min} to {max}"),
            ParamKind::Number { min, max } if *min == f64::MIN && *max == f64::MAX => {
                "a number".into()
            }
            ParamKind::Number { min, max } => format!("a number from {min} to {max}"),
            ParamKind::Flag => "true or false".into(),
            ParamKind::Choice(words) => format!("one of {}", words.join(", ")),
            ParamKind::Text { expected } => expected.to_string(),
            ParamKind::Numbers { names } => format!("{names} (numbers)"),
        }
    }

    /// `value` as this kind takes it, or None where it does not.
    pub fn parse_value(&self, value: &str) -> Option<ParamValue> {
        let value = value.trim();
        match *self {
            ParamKind::Integer { min, max } => value
                .parse::<i64>()
                .ok()
                .filter(|v| (min..=max).contains(v))
                .map(ParamValue::Integer),
            ParamKind::Number { min, max } => value
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite() && (min..=max).contains(v))
                .map(ParamValue::Number),
            ParamKind::Flag => value.parse().ok().map(ParamValue::Flag),
            ParamKind::Choice(words) => words
                .iter()
                .find(|w| **w == value)
                .map(|w| ParamValue::Word(w.to_string())),
            ParamKind::Text { .. } => Some(ParamValue::Word(value.to_string())),
            ParamKind::Numbers { names } => {
                let numbers: Vec<f64> = value
                    .split(',')
                    .map(|v| v.trim().parse::<f64>().ok().filter(|v| v.is_finite()))
                    .collect::<Option<_>>()?;
                (numbers.len() == names.split(',').count()).then_some(ParamValue::Numbers(numbers))
            }
        }
    }
}

impl ParamSpec {
    /// Parses `value` for this parameter of `technique`.
    pub fn parse(&self, technique: &'static str, value: &str) -> Result<ParamValue, ParamError> {
        self.kind.parse_value(value).ok_or_else(|| ParamError {
            owner: technique,
            name: self.name.to_string(),
            value: value.trim().to_string(),
            reason: format!("expected {}", self.kind.describe()),
        })
    }
}

/// A parameter as declared, before the [`params!`](crate::params) block names it after its
/// field.
#[derive(Clone, Copy, Debug)]
pub struct Param {
    pub kind: ParamKind,
    pub default: &'static str,
    pub doc: &'static str,
    pub invalidates: Invalidates,
}

impl Param {
    /// The spec of the parameter called `name`.
    pub const fn named(self, name: &'static str) -> ParamSpec {
        ParamSpec {
            name,
            kind: self.kind,
            default: self.default,
            doc: self.doc,
            invalidates: self.invalidates,
        }
    }
}

/// A type a parameter is held in: made from a value its spec has parsed, and written back as
/// the text `specula methods`, reports and presets show.
pub trait ParamType: Sized {
    /// The value, or why the technique cannot take it (a spec's kind has been checked).
    fn from_param(value: &ParamValue) -> Result<Self, String>;
    fn to_param(&self) -> String;
}

macro_rules! numeric_param_type {
    ($($ty:ty => $read:ident),* $(,)?) => {
        $(impl ParamType for $ty {
            fn from_param(value: &ParamValue) -> Result<Self, String> {
                Ok(value.$read() as $ty)
            }
            fn to_param(&self) -> String {
                self.to_string()
            }
        })*
    };
}

numeric_param_type!(u32 => integer, u64 => integer, usize => integer, i64 => integer,
    f32 => number, f64 => number);

impl ParamType for bool {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        Ok(value.flag())
    }
    fn to_param(&self) -> String {
        self.to_string()
    }
}

/// A set of parameters read and written by name: what a [`params!`](crate::params) block
/// implements, and what a technique's `params` hands out.
pub trait ParamSet {
    /// The parameter's value as text; None for a name the set does not have.
    fn get(&self, name: &str) -> Option<String>;
    /// Sets the parameter from a value its spec has parsed; None for a name the set does not
    /// have, an error for a value the type cannot take.
    fn set(&mut self, name: &str, value: &ParamValue) -> Option<Result<(), String>>;
}

/// No parameters (a technique without any).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NoParams;

impl NoParams {
    pub const SPECS: &'static [ParamSpec] = &[];
}

impl ParamSet for NoParams {
    fn get(&self, _: &str) -> Option<String> {
        None
    }
    fn set(&mut self, _: &str, _: &ParamValue) -> Option<Result<(), String>> {
        None
    }
}

/// The value of `spec`'s default, for a [`params!`](crate::params) block's `Default`. A default
/// its own spec refuses is a bug in the declaration, which every method's lifecycle test meets
/// at once (`every_parameter_the_parser_accepts_is_listed_and_every_listed_one_is_accepted`).
pub fn default_of<T: ParamType>(spec: &ParamSpec) -> T {
    spec.parse("a declaration", spec.default)
        .map_err(|e| e.to_string())
        .and_then(|value| T::from_param(&value))
        .unwrap_or_else(|e| panic!("parameter {}: its default does not parse: {e}", spec.name))
}

/// Declares a struct of parameters, each once: `field: Type = Param { .. }` (or a shared
/// `Param` constant). Generates the struct (public fields), its `SPECS` in declaration order
/// (named after the fields), `Default` from the specs' defaults, and [`ParamSet`].
#[macro_export]
macro_rules! params {
    ($($declaration:tt)*) => {
        $crate::declared_set!(ParamSpec, default_of, $($declaration)*);
    };
}

/// What [`params!`](crate::params) and [`options!`](crate::options) both generate, from the
/// spec type their declarations name themselves as and the function that parses a default.
#[doc(hidden)]
#[macro_export]
macro_rules! declared_set {
    (
        $spec:ident, $default_of:ident,
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $($field:ident : $ty:ty = $declared:expr),* $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Debug, PartialEq)]
        $vis struct $name {
            $(pub $field: $ty,)*
        }

        impl $name {
            /// Every spec, in declaration order.
            pub const SPECS: &'static [$crate::$spec] =
                &[$($declared.named(stringify!($field))),*];
        }

        impl Default for $name {
            fn default() -> Self {
                $name {
                    $($field: $crate::$default_of(&$declared.named(stringify!($field))),)*
                }
            }
        }

        impl $crate::ParamSet for $name {
            fn get(&self, name: &str) -> Option<String> {
                match name {
                    $(stringify!($field) => Some($crate::ParamType::to_param(&self.$field)),)*
                    _ => None,
                }
            }
            fn set(
                &mut self,
                name: &str,
                value: &$crate::ParamValue,
            ) -> Option<Result<(), String>> {
                match name {
                    $(stringify!($field) => Some(
                        <$ty as $crate::ParamType>::from_param(value).map(|v| self.$field = v),
                    ),)*
                    _ => None,
                }
            }
        }
    };
}

/// Makes an enum a parameter type of one word per variant: `choice!(Exit { None = "none",
/// Sphere = "sphere" })` gives `Exit::WORDS` (for [`ParamKind::Choice`]), `Exit::word` and
/// [`ParamType`].
#[macro_export]
macro_rules! choice {
    ($ty:ident { $($variant:ident = $word:literal),+ $(,)? }) => {
        impl $ty {
            /// Every word, in declaration order.
            pub const WORDS: &'static [&'static str] = &[$($word),+];

            /// The word users type for this value.
            pub fn word(self) -> &'static str {
                match self {
                    $($ty::$variant => $word,)+
                }
            }
        }

        impl $crate::ParamType for $ty {
            fn from_param(value: &$crate::ParamValue) -> Result<Self, String> {
                match value.word() {
                    $($word => Ok($ty::$variant),)+
                    other => Err(format!("expected one of {}, not {other}", $ty::WORDS.join(", "))),
                }
            }
            fn to_param(&self) -> String {
                self.word().to_string()
            }
        }
    };
}

/// The parameter table a technique's module doc holds (name, what it takes, default, what a
/// change redoes, what it does), as Markdown in `//!` lines: the lifecycle test holds every
/// module doc to it.
pub fn doc_table(specs: &[ParamSpec]) -> String {
    let mut table = String::from(
        "//! | parameter | takes | default | a change redoes | what it does |\n//! |---|---|---|---|---|\n",
    );
    for spec in specs {
        table.push_str(&format!(
            "//! | `{}` | {} | `{}` | {} | {} |\n",
            spec.name,
            spec.kind.describe().replace('|', "\\|"),
            spec.default,
            spec.invalidates.describe(),
            spec.doc.replace('|', "\\|"),
        ));
    }
    table
}
