//! The regulations' tables: each class's prescribed fields, whose eyes judge them, and the
//! rules its mirror's surface must meet, with the paragraph each comes from.

use super::*;

pub(super) const R46: &str = "UN Regulation No. 46, 04 series of amendments";

/// The regulations `--regulation` knows. Every figure is the one the cited paragraph states as
/// we read it; docs/analyses/mirror-view.md says which were checked against the text and which not.
/// The names of [`REGULATIONS`], in order (the `regulation` option's choices; a test holds the
/// two lists equal).
pub const REGULATION_NAMES: &[&str] = &[
    "r46-i",
    "r46-ii",
    "r46-iii",
    "r46-iv",
    "r46-v",
    "fmvss111",
    "fmvss111-convex",
];

pub const REGULATIONS: &[Regulation] = &[
    Regulation {
        name: "r46-i",
        title: "UN R46 class I: interior rear-view mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: true,
        fields: &[FieldSpec {
            name: "20 m wide from 60 m behind to the horizon",
            lateral: Lateral::AboutMedian { width: 20.0 },
            from_m: 60.0,
            to_m: None,
            source: "R46 §15.2.4.1; 71/127/EEC Annex III §5.2",
        }],
        surface: r46_surface(
            1.2,
            false,
            Some(RectangleRule {
                a_numerator_mm: 150.0,
                segment_mm: None,
                either_way: true,
            }),
            "R46 §6.1.2.1.1, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-ii",
        title: "UN R46 class II: main exterior rear-view mirror, large",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "5 m wide from 30 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 5.0,
                },
                from_m: 30.0,
                to_m: None,
                source: "R46 §15.2.4.2",
            },
            FieldSpec {
                name: "1 m wide from 4 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 1.0,
                },
                from_m: 4.0,
                to_m: None,
                source: "R46 §15.2.4.2",
            },
        ],
        surface: r46_surface(
            1.2,
            true,
            Some(RectangleRule {
                a_numerator_mm: 170.0,
                segment_mm: Some(200.0),
                either_way: false,
            }),
            "R46 §6.1.2.1.2.1, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-iii",
        title: "UN R46 class III: main exterior rear-view mirror, small",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "4 m wide from 20 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 4.0,
                },
                from_m: 20.0,
                to_m: None,
                source: "R46 §15.2.4.3",
            },
            FieldSpec {
                name: "1 m wide from 4 m behind to the horizon",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 1.0,
                },
                from_m: 4.0,
                to_m: None,
                source: "R46 §15.2.4.3",
            },
        ],
        surface: r46_surface(
            1.2,
            true,
            Some(RectangleRule {
                a_numerator_mm: 130.0,
                segment_mm: Some(70.0),
                either_way: false,
            }),
            "R46 §6.1.2.1.2.2, §6.1.2.2",
        ),
    },
    Regulation {
        name: "r46-iv",
        title: "UN R46 class IV: wide-angle exterior mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[
            FieldSpec {
                name: "15 m wide from 10 m to 25 m behind",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 15.0,
                },
                from_m: 10.0,
                to_m: Some(25.0),
                source: "R46 §15.2.4.4",
            },
            FieldSpec {
                name: "4.5 m wide from 1.5 m to 10 m behind",
                lateral: Lateral::FromSide {
                    inner: 0.0,
                    outer: 4.5,
                },
                from_m: 1.5,
                to_m: Some(10.0),
                source: "R46 §15.2.4.4",
            },
        ],
        surface: r46_surface(0.3, true, None, "R46 §6.1.2.2"),
    },
    Regulation {
        name: "r46-v",
        title: "UN R46 class V: close-proximity exterior mirror",
        edition: R46,
        eyes: EyeRule::OcularPoints,
        interior: false,
        fields: &[FieldSpec {
            name: "2 m out from 1.75 m behind to 1 m ahead",
            lateral: Lateral::FromSide {
                inner: 0.0,
                outer: 2.0,
            },
            from_m: -1.0,
            to_m: Some(1.75),
            source: "R46 §15.2.4.5",
        }],
        surface: r46_surface(0.3, true, None, "R46 §6.1.2.2"),
    },
    Regulation {
        name: "fmvss111",
        title: "FMVSS No. 111, passenger car, driver's side outside mirror",
        edition: "49 CFR 571.111 (FMVSS No. 111)",
        eyes: EyeRule::DriversEyes,
        interior: false,
        fields: &[FieldSpec {
            name: "2.4 m wide from 10.7 m behind the eyes to the horizon",
            lateral: Lateral::FromSide {
                inner: 0.0,
                outer: 2.4,
            },
            from_m: 10.7,
            to_m: None,
            source: "FMVSS 111 S5.2.1 (read as a field: the 2.4 m line at 10.7 m, to the horizon)",
        }],
        surface: SurfaceRule {
            spherical: None,
            flat: true,
            convex: None,
            rectangle: None,
            source: "FMVSS 111 S5.2.1 (unit magnification)",
        },
    },
    Regulation {
        name: "fmvss111-convex",
        title: "FMVSS No. 111, passenger car, passenger's side convex outside mirror",
        edition: "49 CFR 571.111 (FMVSS No. 111)",
        eyes: EyeRule::DriversEyes,
        interior: false,
        // S5.4 prescribes no field for the convex mirror: its surface is what is judged.
        fields: &[],
        surface: SurfaceRule {
            spherical: None,
            flat: false,
            convex: Some(ConvexRule {
                min_average_m: 0.889,
                max_average_m: 1.651,
                max_deviation_share: 0.125,
            }),
            rectangle: None,
            source: "FMVSS 111 S5.4.1, S12",
        },
    },
];

/// R46's rule for a spherical mirror's surface: r at least `min_radius_m`, an aspherical part
/// allowed on `exterior` mirrors, and the rectangle.
pub(super) const fn r46_surface(
    min_radius_m: f64,
    exterior: bool,
    rectangle: Option<RectangleRule>,
    source: &'static str,
) -> SurfaceRule {
    SurfaceRule {
        spherical: Some(SphericalRule {
            min_radius_m,
            aspherical_part_allowed: exterior,
        }),
        flat: false,
        convex: None,
        rectangle,
        source,
    }
}
