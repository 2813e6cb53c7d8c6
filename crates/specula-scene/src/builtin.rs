//! Built-in scenes, one per paper's test setup. Meshes they use are embedded in the binary
//! (see scenes/meshes/README.md for provenance), so they work from any directory.

use glam::{Mat4, Quat, Vec2, Vec3};

use crate::generators::{self, LensSpec};
use crate::loaders::{parse_obj, toml_scene::fit_meshes};
use crate::{Background, Camera, Light, Material, MaterialKind, Mesh, Scene, SceneError, Texture};

/// The scene commands use when given none.
pub const DEFAULT_SCENE: &str = "door-mirror";

type Builder = fn() -> Result<Scene, SceneError>;

/// (name, one-line description, constructor) of every built-in scene.
const SCENES: &[(&str, &str, Builder)] = &[
    ("door-mirror", "free-form convex car door mirror (bicubic patch, 49 vertices) reflecting a small town with red marker balls [pvrr]", door_mirror),
    ("spectacle-lens", "dispersive meniscus spectacle lens (back vertex power -3.02 D at n_d = 1.61; the thin-lens sum F1 + F2 is -3.05 D; ~1,900 triangles) 6.5 cm in front of the eye, over a colour chart [pvrr]", spectacle_lens),
    ("teapot-box", "mirror Utah teapot in a box room with coloured walls [distance-maps]", teapot_box),
    ("glass-dragon", "glass bunny refracting the Stanford dragon and two textured planes behind it [image-space]", glass_dragon),
    ("mirror-teapot-bunny", "mirror teapot reflecting the Stanford bunny and dragon on a checkered floor [c3rc]", mirror_teapot_bunny),
    ("truck-cover", "concave glass instrument cover in front of a dial, with a bright side window that can glare [vertex-tracing]", truck_cover),
];

pub fn names() -> Vec<&'static str> {
    SCENES.iter().map(|s| s.0).collect()
}

/// (name, description) pairs, in display order.
pub fn list() -> Vec<(&'static str, &'static str)> {
    SCENES.iter().map(|s| (s.0, s.1)).collect()
}

pub fn by_name(name: &str) -> Option<Result<Scene, SceneError>> {
    SCENES.iter().find(|s| s.0 == name).map(|s| (s.2)())
}

const BUNNY_OBJ: &str = include_str!("../../../scenes/meshes/bunny.obj");
const DRAGON_OBJ: &str = include_str!("../../../scenes/meshes/dragon_res4.obj");

fn embedded_mesh(name: &str, text: &str, fit: f32) -> Result<Mesh, SceneError> {
    let mut meshes = parse_obj(name, text)?;
    fit_meshes(&mut meshes, fit);
    let mut mesh = meshes
        .into_iter()
        .next()
        .ok_or_else(|| SceneError::invalid(name, "no mesh"))?;
    mesh.name = name.to_string();
    Ok(mesh)
}

struct SceneBuilder {
    scene: Scene,
}

impl SceneBuilder {
    fn new(name: &str, camera: Camera, background: Vec3, ambient: f32) -> Self {
        let mut scene = Scene::new(name);
        scene.camera = camera;
        scene.background = Background::Color(background);
        scene.ambient = Vec3::splat(ambient);
        SceneBuilder { scene }
    }

    fn material(&mut self, material: Material) -> usize {
        self.scene.materials.push(material);
        self.scene.materials.len() - 1
    }

    fn textured(&mut self, mut material: Material, texture: Texture) -> usize {
        self.scene.textures.push(texture);
        material.texture = Some(self.scene.textures.len() - 1);
        self.material(material)
    }

    fn add(&mut self, name: &str, mut mesh: Mesh, material: usize, world_from_object: Mat4) {
        mesh.transform(world_from_object);
        // Slivers at tessellated poles can round to zero area once moved: a tessellation
        // artefact, not bad input, so they go silently here.
        mesh.drop_degenerate_triangles();
        mesh.material = material;
        mesh.name = name.to_string();
        self.scene.meshes.push(mesh);
    }

    fn light(&mut self, light: Light) {
        self.scene.lights.push(light);
    }

    fn finish(mut self) -> Result<Scene, SceneError> {
        let source = format!("built-in scene '{}'", self.scene.name);
        self.scene.finalize(&source)?;
        Ok(self.scene)
    }
}

fn camera(eye: [f32; 3], target: [f32; 3], fov_y_deg: f32) -> Camera {
    Camera {
        eye: Vec3::from_array(eye),
        target: Vec3::from_array(target),
        up: Vec3::Y,
        fov_y_deg,
        aspect: Some(4.0 / 3.0),
    }
}

fn at(translation: [f32; 3]) -> Mat4 {
    Mat4::from_translation(Vec3::from_array(translation))
}

fn checker(name: &str, squares: u32, a: Vec3, b: Vec3) -> Texture {
    Texture::checker(name, squares, 256, a, b)
}

fn srgb(r: u8, g: u8, b: u8) -> Vec3 {
    use crate::texture::srgb_to_linear;
    Vec3::new(
        srgb_to_linear(r as f32 / 255.0),
        srgb_to_linear(g as f32 / 255.0),
        srgb_to_linear(b as f32 / 255.0),
    )
}

/// The 24 patches of a ColorChecker-style chart (approximate sRGB values), 6 × 4, with black
/// borders between patches.
fn colour_chart() -> Texture {
    const PATCHES: [[u8; 3]; 24] = [
        [115, 82, 68],
        [194, 150, 130],
        [98, 122, 157],
        [87, 108, 67],
        [133, 128, 177],
        [103, 189, 170],
        [214, 126, 44],
        [80, 91, 166],
        [193, 90, 99],
        [94, 60, 108],
        [157, 188, 64],
        [224, 163, 46],
        [56, 61, 150],
        [70, 148, 73],
        [175, 54, 60],
        [231, 199, 31],
        [187, 86, 149],
        [8, 133, 161],
        [243, 243, 242],
        [200, 200, 200],
        [160, 160, 160],
        [122, 122, 121],
        [85, 85, 85],
        [52, 52, 52],
    ];
    Texture::procedural("colour chart", 600, 400, |uv| {
        let (x, y) = (uv.x * 6.0, uv.y * 4.0);
        let (fx, fy) = (x.fract(), y.fract());
        if !(0.08..0.92).contains(&fx) || !(0.08..0.92).contains(&fy) {
            return Vec3::splat(0.01);
        }
        let [r, g, b] = PATCHES[(y as usize).min(3) * 6 + (x as usize).min(5)];
        srgb(r, g, b)
    })
}

fn door_mirror() -> Result<Scene, SceneError> {
    door_mirror_tessellated(6)
}

/// The `door-mirror` scene with its mirror patch cut into `quads` × `quads` quads
/// ((quads + 1)² vertices; the built-in scene uses 6, i.e. 49 vertices), for studies of how
/// accuracy scales with tessellation.
pub fn door_mirror_tessellated(quads: u32) -> Result<Scene, SceneError> {
    let mut b = SceneBuilder::new(
        "door-mirror",
        camera([0.28, 0.06, 0.75], [0.0, 0.0, 0.0], 22.0),
        Vec3::new(0.45, 0.62, 0.9),
        0.35,
    );
    let mirror = b.material(Material::mirror("mirror glass", Vec3::splat(0.9)));
    let housing = b.material(Material::diffuse("housing", Vec3::splat(0.04)));
    let ground = b.material(Material::diffuse("asphalt", Vec3::new(0.25, 0.26, 0.24)));
    let red = b.material(Material::diffuse("red marker", Vec3::new(0.8, 0.03, 0.02)));
    let walls = [
        Vec3::new(0.75, 0.68, 0.55),
        Vec3::new(0.55, 0.6, 0.7),
        Vec3::new(0.7, 0.45, 0.35),
        Vec3::new(0.85, 0.85, 0.8),
    ]
    .map(|c| b.material(Material::diffuse("building", c)));
    // By default a 7 × 7 vertex patch: 49 vertices, as in the paper's door mirror.
    let patch = generators::bicubic_patch(&generators::door_mirror_control_points(), quads);
    b.add("door mirror", patch, mirror, Mat4::IDENTITY);
    b.add(
        "mirror housing",
        generators::cuboid(Vec3::new(0.23, 0.16, 0.05)),
        housing,
        at([0.0, 0.0, -0.03]),
    );
    b.add(
        "ground",
        generators::plane(Vec2::splat(200.0), 1),
        ground,
        at([0.0, -1.0, 0.0]),
    );
    // Buildings behind the driver (+Z), on both sides of a street along Z.
    for k in 0..10 {
        let z = 6.0 + 4.5 * k as f32;
        for (side, x) in [(0, -7.0f32), (1, 7.0)] {
            let height = 3.0 + ((k * 7 + side * 3) % 5) as f32 * 1.8;
            let size = Vec3::new(5.0, height, 3.5);
            b.add(
                "building",
                generators::cuboid(size),
                walls[(k + side) % 4],
                at([
                    x + if side == 0 { -1.0 } else { 1.0 } * (k % 3) as f32,
                    -1.0 + height * 0.5,
                    z,
                ]),
            );
        }
    }
    // Red marker balls along the street: easy to locate in a reflection.
    for k in 0..6 {
        let z = 3.0 + 6.0 * k as f32;
        let x = if k % 2 == 0 { -2.0 } else { 2.0 };
        b.add(
            "marker ball",
            generators::sphere(0.5, 32, 16),
            red,
            at([x, -0.5, z]),
        );
    }
    b.light(Light::Directional {
        direction: Vec3::new(-0.4, -1.0, 0.3).normalize(),
        irradiance: Vec3::splat(2.2),
    });
    b.finish()
}

fn spectacle_lens() -> Result<Scene, SceneError> {
    let mut b = SceneBuilder::new(
        "spectacle-lens",
        camera([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], 55.0),
        Vec3::splat(0.02),
        0.0,
    );
    let chart = b.textured(Material::unlit("colour chart", Vec3::ONE), colour_chart());
    let lens = b.material(Material::new(
        "high-index lens glass",
        // The indices of the paper's chromatic-aberration figure (red, green, blue).
        MaterialKind::Dielectric {
            ior: Vec3::new(1.60, 1.61, 1.62),
            thin_walled: false,
        },
        Vec3::ONE,
    ));
    let spec = LensSpec {
        front_radius: 0.12,
        back_radius: 0.075,
        center_thickness: 0.002,
        diameter: 0.05,
        rings: 10,
        segments: 48,
    };
    // Light travels +Z in the lens frame, towards the eye: the back vertex sits 6.5 cm away.
    b.add(
        "spectacle lens",
        generators::lens(&spec)?,
        lens,
        at([0.0, 0.0, -0.065 - 0.002]),
    );
    let chart_plane = generators::plane(Vec2::new(0.9, 0.6), 1);
    let facing_eye = Mat4::from_translation(Vec3::new(0.0, 0.0, -0.6))
        * Mat4::from_rotation_x(std::f32::consts::FRAC_PI_2);
    b.add("colour chart", chart_plane, chart, facing_eye);
    b.finish()
}

/// The six inward-facing walls of a cubic room, floor at y = 0.
fn room(b: &mut SceneBuilder, size: f32, left: usize, right: usize, rest: usize) {
    use std::f32::consts::{FRAC_PI_2, PI};
    let h = size * 0.5;
    let wall = || generators::plane(Vec2::splat(size), 1);
    b.add("floor", wall(), rest, at([0.0, 0.0, 0.0]));
    b.add(
        "ceiling",
        wall(),
        rest,
        at([0.0, size, 0.0]) * Mat4::from_rotation_x(PI),
    );
    b.add(
        "back wall",
        wall(),
        rest,
        at([0.0, h, -h]) * Mat4::from_rotation_x(FRAC_PI_2),
    );
    b.add(
        "left wall",
        wall(),
        left,
        at([-h, h, 0.0]) * Mat4::from_rotation_z(-FRAC_PI_2),
    );
    b.add(
        "right wall",
        wall(),
        right,
        at([h, h, 0.0]) * Mat4::from_rotation_z(FRAC_PI_2),
    );
    b.add(
        "front wall",
        wall(),
        rest,
        at([0.0, h, h]) * Mat4::from_rotation_x(-FRAC_PI_2),
    );
}

fn teapot_box() -> Result<Scene, SceneError> {
    let mut b = SceneBuilder::new(
        "teapot-box",
        camera([0.0, 0.6, 0.55], [0.0, 0.2, -0.1], 62.0),
        Vec3::ZERO,
        0.12,
    );
    let red = b.material(Material::diffuse("red wall", Vec3::new(0.63, 0.06, 0.05)));
    let green = b.material(Material::diffuse("green wall", Vec3::new(0.12, 0.45, 0.09)));
    let white = b.textured(
        Material::diffuse("tiled wall", Vec3::ONE),
        checker("tiles", 8, Vec3::splat(0.75), Vec3::splat(0.45)),
    );
    let chrome = b.material(Material::mirror("chrome", Vec3::new(0.95, 0.93, 0.88)));
    let blue = b.material(Material::diffuse("blue", Vec3::new(0.1, 0.2, 0.7)));
    room(&mut b, 1.2, red, green, white);
    b.add(
        "teapot",
        generators::teapot(8),
        chrome,
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.1),
            Quat::from_rotation_y(0.5),
            Vec3::new(0.0, 0.0, -0.1),
        ),
    );
    b.add(
        "blue cube",
        generators::cuboid(Vec3::splat(0.2)),
        blue,
        at([0.35, 0.1, -0.35]) * Mat4::from_rotation_y(0.4),
    );
    b.add(
        "yellow ball",
        generators::sphere(0.1, 32, 16),
        red,
        at([-0.35, 0.1, 0.15]),
    );
    b.light(Light::Point {
        position: Vec3::new(0.0, 1.1, 0.1),
        intensity: Vec3::splat(0.9),
    });
    b.finish()
}

fn glass_dragon() -> Result<Scene, SceneError> {
    use std::f32::consts::FRAC_PI_2;
    let mut b = SceneBuilder::new(
        "glass-dragon",
        camera([0.0, 0.28, 0.9], [0.0, 0.15, 0.0], 40.0),
        Vec3::new(0.02, 0.02, 0.03),
        0.15,
    );
    let glass = b.material(Material::glass("glass", 1.5));
    let gold = b.material(Material::diffuse("dragon", Vec3::new(0.7, 0.5, 0.15)));
    let floor = b.textured(
        Material::diffuse("floor", Vec3::ONE),
        checker(
            "floor checker",
            10,
            Vec3::splat(0.8),
            Vec3::new(0.1, 0.1, 0.3),
        ),
    );
    let wall = b.textured(
        Material::diffuse("wall", Vec3::ONE),
        checker(
            "wall checker",
            12,
            Vec3::new(0.8, 0.75, 0.6),
            Vec3::new(0.5, 0.15, 0.1),
        ),
    );
    let bunny = embedded_mesh("bunny", BUNNY_OBJ, 0.28)?;
    b.add("glass bunny", bunny, glass, at([0.0, 0.0, 0.15]));
    let dragon = embedded_mesh("dragon", DRAGON_OBJ, 0.45)?;
    b.add("dragon", dragon, gold, at([0.0, 0.0, -0.3]));
    b.add(
        "floor",
        generators::plane(Vec2::splat(2.0), 1),
        floor,
        Mat4::IDENTITY,
    );
    b.add(
        "back wall",
        generators::plane(Vec2::splat(2.0), 1),
        wall,
        at([0.0, 1.0, -0.7]) * Mat4::from_rotation_x(FRAC_PI_2),
    );
    b.light(Light::Point {
        position: Vec3::new(0.6, 1.2, 1.0),
        intensity: Vec3::splat(2.0),
    });
    b.finish()
}

fn mirror_teapot_bunny() -> Result<Scene, SceneError> {
    let mut b = SceneBuilder::new(
        "mirror-teapot-bunny",
        camera([0.0, 0.45, 1.1], [0.0, 0.12, 0.0], 40.0),
        Vec3::new(0.3, 0.35, 0.45),
        0.25,
    );
    let chrome = b.material(Material::mirror("chrome", Vec3::splat(0.92)));
    let clay = b.material(Material::diffuse("bunny", Vec3::new(0.75, 0.7, 0.65)));
    let jade = b.material(Material::diffuse("dragon", Vec3::new(0.2, 0.6, 0.3)));
    let floor = b.textured(
        Material::diffuse("floor", Vec3::ONE),
        checker("floor checker", 12, Vec3::splat(0.8), Vec3::splat(0.15)),
    );
    b.add(
        "teapot",
        generators::teapot(8),
        chrome,
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.08),
            Quat::from_rotation_y(-0.3),
            Vec3::ZERO,
        ),
    );
    b.add(
        "bunny",
        embedded_mesh("bunny", BUNNY_OBJ, 0.25)?,
        clay,
        at([-0.38, 0.0, 0.1]),
    );
    b.add(
        "dragon",
        embedded_mesh("dragon", DRAGON_OBJ, 0.35)?,
        jade,
        at([0.4, 0.0, 0.0]) * Mat4::from_rotation_y(-1.2),
    );
    b.add(
        "floor",
        generators::plane(Vec2::splat(3.0), 1),
        floor,
        Mat4::IDENTITY,
    );
    b.light(Light::Directional {
        direction: Vec3::new(0.5, -1.0, -0.4).normalize(),
        irradiance: Vec3::splat(2.0),
    });
    b.finish()
}

/// A dial face: ticks and numerals-like blocks around a dark disc.
fn dial_texture() -> Texture {
    Texture::procedural("dial", 512, 512, |uv| {
        let p = (uv - Vec2::splat(0.5)) * 2.0;
        let (r, angle) = (p.length(), p.y.atan2(p.x));
        let tick = (angle / std::f32::consts::TAU * 40.0).rem_euclid(1.0);
        if r > 0.98 {
            Vec3::splat(0.02)
        } else if r > 0.78 && r < 0.92 && !(0.1..0.9).contains(&tick) {
            Vec3::new(0.95, 0.95, 0.9)
        } else if (p.x - p.y * 0.2).abs() < 0.02 && p.y > -0.1 && p.y < 0.7 {
            Vec3::new(1.0, 0.3, 0.05)
        } else {
            Vec3::splat(0.03)
        }
    })
}

fn truck_cover() -> Result<Scene, SceneError> {
    use std::f32::consts::FRAC_PI_2;
    let mut b = SceneBuilder::new(
        "truck-cover",
        camera([0.0, 0.12, 0.7], [0.0, 0.0, 0.0], 35.0),
        Vec3::splat(0.01),
        0.1,
    );
    let glass = b.material(Material::glass("cover glass", 1.52));
    let dial = b.textured(Material::unlit("dial", Vec3::ONE), dial_texture());
    let dash = b.material(Material::diffuse("dashboard", Vec3::splat(0.06)));
    let window = b.material(Material::unlit("side window", Vec3::new(6.0, 6.0, 5.5)));
    // Meniscus shell, concave towards the driver (+Z): equal radii keep its thickness constant.
    let cover = generators::lens(&LensSpec {
        front_radius: 0.4,
        back_radius: 0.4,
        center_thickness: 0.003,
        diameter: 0.26,
        rings: 16,
        segments: 64,
    })?;
    b.add("cover glass", cover, glass, at([0.0, 0.0, 0.0]));
    let dial_plane = generators::plane(Vec2::splat(0.22), 1);
    b.add(
        "dial",
        dial_plane,
        dial,
        at([0.0, 0.0, -0.06]) * Mat4::from_rotation_x(FRAC_PI_2),
    );
    b.add(
        "instrument panel",
        generators::cuboid(Vec3::new(0.6, 0.35, 0.02)),
        dash,
        at([0.0, 0.0, -0.075]),
    );
    b.add(
        "dashboard",
        generators::plane(Vec2::new(1.6, 0.8), 1),
        dash,
        at([0.0, -0.18, 0.3]),
    );
    // The bright side window, beside and behind the driver, facing the cover: the concave
    // glass mirrors it towards the driver's eye near the cover's right edge.
    let window_center = Vec3::new(-0.45, -0.05, 1.1);
    b.add(
        "side window",
        generators::plane(Vec2::new(0.6, 0.5), 1),
        window,
        Mat4::from_rotation_translation(
            Quat::from_rotation_arc(
                Vec3::Y,
                (Vec3::new(0.1, 0.0, 0.0) - window_center).normalize(),
            ),
            window_center,
        ),
    );
    b.light(Light::Point {
        position: Vec3::new(0.3, 0.6, 0.8),
        intensity: Vec3::splat(0.5),
    });
    b.finish()
}
