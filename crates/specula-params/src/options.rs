//! An analysis's options, each declared once, with what a technique's parameters lack: a unit,
//! a group (the help's heading, the panel's section), whether it may be given several times and
//! whether it must be given. From one [`options!`](crate::options) block come the command's
//! flags, the viewer's script keys and panel controls, and the docs' option table, so the front
//! ends cannot drift apart.
//!
//! ```
//! use specula_params::{apply_option, options, Opt, ParamKind};
//!
//! options! {
//!     /// A toy analysis's options.
//!     pub struct ToyOptions {
//!         range: f64 = Opt::new(ParamKind::Number { min: 0.0, max: 1e4 }, "80", "m",
//!             "ground farther than this is not counted"),
//!         r_point: Option<glam::Vec3> = Opt::new(ParamKind::Numbers { names: "X,Y,Z" }, "", "m",
//!             "the driver's R point (default: 635 mm below the camera's eye)"),
//!     }
//! }
//! let mut o = ToyOptions::default();
//! assert_eq!((o.range, o.r_point), (80.0, None));
//! apply_option(ToyOptions::SPECS, &mut o, "toy", "r_point", "0,1,2").unwrap();
//! assert_eq!(o.r_point, Some(glam::Vec3::new(0.0, 1.0, 2.0)));
//! assert!(apply_option(ToyOptions::SPECS, &mut o, "toy", "range", "-1").is_err());
//! ```

use glam::Vec3;

use crate::{ParamError, ParamKind, ParamSet, ParamType, ParamValue};

/// One option of an analysis: the single source of its flag, script key, panel control and
/// documentation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OptionSpec {
    /// Its name: the script key and the JSON's; the flag is `--` and the name with `-` for `_`.
    pub name: &'static str,
    pub kind: ParamKind,
    /// The default as text; empty where the option has none and the analysis's own rule (its
    /// doc says which) decides.
    pub default: &'static str,
    /// The unit its numbers are in (`m`, `mm`, `°`, `cd/m²`), empty for none.
    pub unit: &'static str,
    /// One line: what it does, and the rule that decides when it is left out.
    pub doc: &'static str,
    /// The heading it is listed under (empty: the analysis's first).
    pub group: &'static str,
    /// It may be given several times (each value in turn; `;` between them as text).
    pub repeatable: bool,
    /// It must be given.
    pub required: bool,
}

/// An option as declared, before the [`options!`](crate::options) block names it after its
/// field.
#[derive(Clone, Copy, Debug)]
pub struct Opt {
    kind: ParamKind,
    default: &'static str,
    unit: &'static str,
    doc: &'static str,
    group: &'static str,
    repeatable: bool,
    required: bool,
}

impl Opt {
    pub const fn new(
        kind: ParamKind,
        default: &'static str,
        unit: &'static str,
        doc: &'static str,
    ) -> Opt {
        Opt {
            kind,
            default,
            unit,
            doc,
            group: "",
            repeatable: false,
            required: false,
        }
    }

    /// A name of one of the scene's objects.
    pub const fn object(doc: &'static str) -> Opt {
        Opt::new(
            ParamKind::Text {
                expected: OBJECT_NAME,
            },
            "",
            "",
            doc,
        )
    }

    /// Any finite number (the analysis checks its range and says why a value is refused).
    pub const fn number(default: &'static str, unit: &'static str, doc: &'static str) -> Opt {
        Opt::new(
            ParamKind::Number {
                min: f64::MIN,
                max: f64::MAX,
            },
            default,
            unit,
            doc,
        )
    }

    /// Finite numbers given together (`names`: `X0,Z0,X1,Z1`), none by default.
    pub const fn numbers(names: &'static str, unit: &'static str, doc: &'static str) -> Opt {
        Opt::new(ParamKind::Numbers { names }, "", unit, doc)
    }

    /// A point X,Y,Z in metres (world space), none by default.
    pub const fn point(doc: &'static str) -> Opt {
        Opt::new(ParamKind::Numbers { names: "X,Y,Z" }, "", "m", doc)
    }

    /// A flag, false by default.
    pub const fn flag(doc: &'static str) -> Opt {
        Opt::new(ParamKind::Flag, "false", "", doc)
    }

    pub const fn group(mut self, group: &'static str) -> Opt {
        self.group = group;
        self
    }

    pub const fn repeatable(mut self) -> Opt {
        self.repeatable = true;
        self
    }

    pub const fn required(mut self) -> Opt {
        self.required = true;
        self
    }

    /// The spec of the option called `name`.
    pub const fn named(self, name: &'static str) -> OptionSpec {
        OptionSpec {
            name,
            kind: self.kind,
            default: self.default,
            unit: self.unit,
            doc: self.doc,
            group: self.group,
            repeatable: self.repeatable,
            required: self.required,
        }
    }
}

/// What an option naming one of the scene's objects takes ([`Opt::object`]).
const OBJECT_NAME: &str = "a name of the scene's objects";

impl OptionSpec {
    /// Whether it names one of the scene's objects (front ends offer the scene's names).
    pub fn names_an_object(&self) -> bool {
        matches!(self.kind, ParamKind::Text { expected } if expected == OBJECT_NAME)
    }

    /// The command-line flag: `--` and the name, `-` for `_`.
    pub fn flag(&self) -> String {
        format!("--{}", self.name.replace('_', "-"))
    }

    /// Parses `value` for this option of `owner`: empty leaves an option without a default
    /// unset; a repeatable option's values are `;`-separated.
    pub fn parse(&self, owner: &'static str, value: &str) -> Result<ParamValue, ParamError> {
        let bad = |reason: String| ParamError {
            owner,
            name: self.name.to_string(),
            value: value.trim().to_string(),
            reason,
        };
        if self.repeatable {
            let items = value.split(';').map(str::trim).filter(|v| !v.is_empty());
            return items
                .map(|item| {
                    self.kind
                        .parse_value(item)
                        .ok_or_else(|| bad(format!("expected {}", self.kind.describe())))
                })
                .collect::<Result<_, _>>()
                .map(ParamValue::List);
        }
        if value.trim().is_empty() && self.default.is_empty() {
            return if self.required {
                Err(bad("it must be given".into()))
            } else {
                Ok(ParamValue::Unset)
            };
        }
        self.kind
            .parse_value(value)
            .ok_or_else(|| bad(format!("expected {}", self.kind.describe())))
    }
}

/// Sets option `name` of `options` (declared by `specs`) from its text.
pub fn apply_option(
    specs: &[OptionSpec],
    options: &mut dyn ParamSet,
    owner: &'static str,
    name: &str,
    value: &str,
) -> Result<(), ParamError> {
    let spec = specs.iter().find(|s| s.name == name).ok_or_else(|| {
        let names: Vec<&str> = specs.iter().map(|s| s.name).collect();
        ParamError {
            owner,
            name: name.to_string(),
            value: value.to_string(),
            reason: format!("{owner}'s options are {}", names.join(", ")),
        }
    })?;
    let parsed = spec.parse(owner, value)?;
    options
        .set(name, &parsed)
        .expect("a declared option is in its set")
        .map_err(|reason| ParamError {
            owner,
            name: name.to_string(),
            value: value.to_string(),
            reason,
        })
}

/// The option table of an analysis's docs (option, takes, unit, default, what it does), as
/// Markdown; a test holds each analysis's doc page to it.
pub fn options_table(specs: &[OptionSpec]) -> String {
    let mut table = String::from(
        "| option | script key | takes | unit | default | what it does |\n|---|---|---|---|---|---|\n",
    );
    for spec in specs {
        let mut takes = spec.kind.describe();
        if spec.repeatable {
            takes.push_str(", repeatable");
        }
        let default = match (spec.required, spec.default) {
            (true, _) => "required".to_string(),
            (false, "") => "–".to_string(),
            (false, d) => format!("`{d}`"),
        };
        table.push_str(&format!(
            "| `{}` | `{}` | {} | {} | {} | {} |\n",
            spec.flag(),
            spec.name,
            takes.replace('|', "\\|"),
            spec.unit,
            default,
            spec.doc.replace('|', "\\|"),
        ));
    }
    table
}

impl ParamType for String {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        Ok(value.to_string())
    }
    fn to_param(&self) -> String {
        self.clone()
    }
}

impl<T: ParamType> ParamType for Option<T> {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        match value {
            ParamValue::Unset => Ok(None),
            other => T::from_param(other).map(Some),
        }
    }
    fn to_param(&self) -> String {
        self.as_ref().map(T::to_param).unwrap_or_default()
    }
}

impl<T: ParamType> ParamType for Vec<T> {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        match value {
            ParamValue::List(items) => items.iter().map(T::from_param).collect(),
            ParamValue::Unset => Ok(Vec::new()),
            other => T::from_param(other).map(|v| vec![v]),
        }
    }
    fn to_param(&self) -> String {
        let texts: Vec<String> = self.iter().map(T::to_param).collect();
        texts.join(";")
    }
}

impl<const N: usize> ParamType for [f64; N] {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        match value {
            ParamValue::Numbers(v) => v
                .as_slice()
                .try_into()
                .map_err(|_| format!("expected {N} numbers")),
            _ => Err(format!("expected {N} numbers")),
        }
    }
    fn to_param(&self) -> String {
        let texts: Vec<String> = self.iter().map(|x| x.to_string()).collect();
        texts.join(",")
    }
}

impl ParamType for Vec3 {
    fn from_param(value: &ParamValue) -> Result<Self, String> {
        <[f64; 3]>::from_param(value).map(|[x, y, z]| Vec3::new(x as f32, y as f32, z as f32))
    }
    fn to_param(&self) -> String {
        format!("{},{},{}", self.x, self.y, self.z)
    }
}

/// The value of `spec`'s default, for an [`options!`](crate::options) block's `Default` (a
/// default its own spec refuses is a bug in the declaration, met by every analysis's tests).
pub fn option_default<T: ParamType>(spec: &OptionSpec) -> T {
    let text = if spec.required { "" } else { spec.default };
    let value = if spec.required {
        Ok(ParamValue::Unset)
    } else {
        spec.parse("a declaration", text).map_err(|e| e.to_string())
    };
    value
        .and_then(|v| T::from_param(&v))
        .unwrap_or_else(|e| panic!("option {}: its default does not parse: {e}", spec.name))
}

/// Declares a struct of an analysis's options, each once: `field: Type = Opt::new(..)`.
/// Generates the struct (public fields), its `SPECS` in declaration order (named after the
/// fields), `Default` from the specs' defaults, and [`ParamSet`].
#[macro_export]
macro_rules! options {
    ($($declaration:tt)*) => {
        $crate::declared_set!(OptionSpec, option_default, $($declaration)*);
    };
}
