//! pvrr's planning, on the CPU: per reflector, the exact per-vertex rays (step 1), the patches
//! and their views (steps 2–3), each vertex's texture coordinate (step 5), level by level for
//! reflectors seen in reflectors, within the frame's budget.

use super::*;

/// What a level of the recursion draws: its reflectors, and (top level, `markers`) the balls.
#[derive(Default)]
pub(super) struct LevelPlan {
    pub(super) reflectors: Vec<ReflectorDraw>,
    pub(super) balls: Vec<Ball>,
}

impl LevelPlan {
    /// Its 1st passes.
    pub(super) fn passes(&self) -> u64 {
        self.reflectors
            .iter()
            .flat_map(|r| &r.patches)
            .map(PatchDraw::passes)
            .sum()
    }

    /// Its patches drawn from a zooming view.
    pub(super) fn zooming_views(&self) -> u64 {
        self.reflectors
            .iter()
            .flat_map(|r| &r.patches)
            .filter(|patch| patch.fill.is_some())
            .count() as u64
    }

    /// Its maps' texels.
    pub(super) fn texels(&self) -> u64 {
        self.reflectors
            .iter()
            .flat_map(|r| &r.patches)
            .map(PatchDraw::texels)
            .sum()
    }

    /// The bytes its 2nd pass writes into the vertex arena.
    pub(super) fn vertex_bytes(&self) -> u64 {
        self.reflectors
            .iter()
            .flat_map(|r| &r.patches)
            .flat_map(|patch| &patch.channels)
            .map(|v| std::mem::size_of_val(v.as_slice()).next_multiple_of(4) as u64)
            .sum()
    }
}

/// A level's plan and, per reflector and patch, the plan of the level that patch's map shows
/// (None: other reflectors appear there as the scene raster draws them, and the patch's corners
/// on them take their traced radiance: [`trace_where_no_nested_level`]).
pub(super) struct PlanTree {
    pub(super) level: LevelPlan,
    pub(super) inner: Vec<Vec<Option<PlanTree>>>,
}

impl PlanTree {
    /// The most vertex-arena bytes in use at once while it is drawn: a level's 2nd pass comes
    /// after its maps, whose nested passes give their room back once submitted.
    pub(super) fn peak_vertex_bytes(&self) -> u64 {
        let nested = self
            .inner
            .iter()
            .flatten()
            .flatten()
            .map(PlanTree::peak_vertex_bytes)
            .max()
            .unwrap_or(0);
        nested.max(self.level.vertex_bytes())
    }
}

/// What the levels below the top may still spend in one frame: 1st passes, map texels and
/// per-vertex rays, across all reflectors and levels. Planned in full, and checked, before
/// any map is drawn or buffer written.
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameBudget {
    pub(super) patches: u64,
    pub(super) texels: u64,
    pub(super) rays: u64,
}

impl FrameBudget {
    /// The nested levels' budget for a frame whose top level is `top` (its per-vertex rays
    /// `top_rays`): `nested_share` times the top level's 1st passes and texels, a quarter of
    /// that times its per-vertex rays (traced on the CPU, they cost more than passes: at 8
    /// times the glass scenes' rays a depth-2 frame took 4.4 times depth 1's), and in all no
    /// more than `frame_patches` 1st passes and `frame_texels` texels.
    pub(super) fn after_top(top: &LevelPlan, top_rays: u64, limits: &FrameLimits) -> FrameBudget {
        let share = |top: u64, frame: u64, total_left: u64| {
            ((top as f64 * limits.nested_share as f64) as u64).min(frame.saturating_sub(total_left))
        };
        FrameBudget {
            patches: share(top.passes(), limits.frame_patches, top.passes()),
            texels: share(top.texels(), limits.frame_texels, top.texels()),
            rays: (top_rays as f64 * limits.nested_share as f64 / 4.0) as u64,
        }
    }

    pub(super) fn covers(&self, patches: u64, texels: u64, rays: u64) -> bool {
        patches <= self.patches && texels <= self.texels && rays <= self.rays
    }

    pub(super) fn spend(&mut self, patches: u64, texels: u64, rays: u64) {
        self.patches -= patches;
        self.texels -= texels;
        self.rays -= rays;
    }
}

/// The frame's limits on nested levels ([`FrameBudget`]).
#[derive(Clone, Copy, Debug)]
pub(super) struct FrameLimits {
    pub(super) nested_share: f32,
    pub(super) frame_patches: u64,
    pub(super) frame_texels: u64,
}

/// The settings steps 1–3 and 5 need.
pub(super) struct PlanSettings {
    pub(super) resolution: u32,
    pub(super) limits: PatchLimits,
    /// Marker radius as a fraction of its distance from the reflector; None: no markers.
    pub(super) markers: Option<f32>,
    pub(super) fit_hits: bool,
    pub(super) zooming: Zooming,
    pub(super) surface_reflection: bool,
    pub(super) internal_reflection: bool,
}

/// Approximate solid angle of `triangles` of `mesh` seen from `eye`.
pub(super) fn solid_angle(mesh: &specula_scene::Mesh, triangles: &[u32], eye: Vec3) -> f32 {
    triangles
        .iter()
        .map(|&t| {
            let [a, b, c] = mesh.triangles[t as usize].map(|i| mesh.positions[i as usize]);
            let area_normal = 0.5 * (b - a).cross(c - a);
            let to_eye = eye - (a + b + c) / 3.0;
            area_normal.dot(to_eye).abs() / to_eye.length().powi(3).max(f32::MIN_POSITIVE)
        })
        .sum()
}

/// Steps 1–3 and 5 for every reflector but `hidden`, seen from `eye`. `cache` (top level, cached
/// mode) holds eye-relative state per mesh; `top` says whether warnings are reported.
#[allow(clippy::too_many_arguments)]
pub(super) fn plan_level(
    p: &Shared,
    settings: &PlanSettings,
    scene: &Scene,
    eye: Vec3,
    hidden: Option<usize>,
    mut cache: Option<(&mut Vec<Option<CachedReflector>>, &EyeFrame)>,
    tally: &mut Tally,
    top: bool,
) -> LevelPlan {
    let mut plan = LevelPlan::default();
    for (index, reflector) in p.reflectors.iter().enumerate() {
        let switched_off = match reflector.interaction {
            Interaction::SurfaceReflect { .. } => !settings.surface_reflection,
            Interaction::InternalReflect { .. } => !settings.internal_reflection,
            _ => false,
        };
        // Inside another reflector's map, a dielectric shows its transmitted light only: its
        // reflections (a few per cent of it) would triple the nested levels' 1st passes.
        let nested_reflection = reflector.additive && !top;
        if Some(reflector.mesh) == hidden || nested_reflection || switched_off {
            continue;
        }
        let slot = cache.as_mut().map(|(slots, frame)| {
            if slots.len() < p.reflectors.len() {
                slots.resize_with(p.reflectors.len(), || None);
            }
            (&mut slots[index], **frame)
        });
        plan_reflector(
            p, settings, scene, reflector, eye, slot, tally, top, &mut plan,
        );
    }
    plan
}

/// The eye-relative state of `mesh` from `slot` if it is still valid there (the cached
/// mode), carried into world space.
pub(super) fn reuse(
    slot: &Option<CachedReflector>,
    frame: &EyeFrame,
    key: &[Vec3],
    interaction: &Interaction,
) -> Option<(MeshPaths, Vec<Patch>)> {
    let cached = slot.as_ref().filter(|c| c.matches(key, interaction))?;
    Some(map_state(
        &cached.paths,
        &cached.patches,
        |q| frame.point_to_world(q),
        |v| frame.vector_to_world(v),
    ))
}

/// Steps 1–3 and 5 for one reflector, appended to `plan`. `slot` is its cache entry and the
/// eye's frame in the cached mode.
#[allow(clippy::too_many_arguments)]
pub(super) fn plan_reflector(
    p: &Shared,
    settings: &PlanSettings,
    scene: &Scene,
    reflector: &Reflector,
    eye: Vec3,
    slot: Option<(&mut Option<CachedReflector>, EyeFrame)>,
    tally: &mut Tally,
    top: bool,
    plan: &mut LevelPlan,
) {
    let (mesh, interaction) = (reflector.mesh, &reflector.interaction);
    let m = &scene.meshes[mesh];
    let key: Option<Vec<Vec3>> = slot.as_ref().map(|(_, frame)| {
        m.positions
            .iter()
            .map(|&v| frame.point_to_local(v))
            .collect()
    });
    let (paths, reused_patches) =
        reflector_paths(p, scene, reflector, eye, slot.as_ref(), key.as_ref(), tally);
    let (hits, drawn): (Vec<Vec<Vec3>>, Vec<Vec<bool>>) = paths
        .channels
        .iter()
        .map(|c| trace_hits(scene, p.accel, &c.exits, p.far_distance))
        .unzip();
    tally.rays += (hits.len() * m.positions.len()) as u64;
    let input = PatchInput {
        mesh: m,
        visible: &paths.visible,
        primary: &paths.channels[paths.channels.len() / 2].exits,
        segments: paths
            .channels
            .iter()
            .zip(&hits)
            .map(|(c, h)| c.exits.iter().zip(h).map(|(s, &p)| (s.origin, p)).collect())
            .collect(),
        drawn: &drawn,
        scene_corners: &p.scene_corners,
        whole_lines: !settings.fit_hits,
    };
    let patches: Vec<Patch> = match reused_patches {
        Some(patches) => patches
            .iter()
            .map(|patch| input.refit(patch, &settings.limits))
            .collect(),
        None => {
            let patches = input.patches(&settings.limits);
            if let Some(((slot, frame), key)) = slot.zip(key) {
                *slot = Some(cache_entry(&frame, key, interaction, &paths, &patches));
            }
            patches
        }
    };
    let unresolved = unresolved_vertices(m, &paths.visible, &hits, &drawn, &patches);
    // A vertex seeing another mirror or lens is traced too: its colour stands in where its
    // patch's map gets no nested level (`trace_where_no_nested_level`).
    let on_reflector: Vec<bool> = (0..m.positions.len())
        .map(|i| paths.visible[i] && drawn.iter().any(|d| !d[i]))
        .collect();
    let to_trace: Vec<bool> = unresolved
        .iter()
        .zip(&on_reflector)
        .map(|(&u, &r)| u || r)
        .collect();
    let traced = (settings.zooming != Zooming::Map)
        .then(|| trace_unresolved(p, scene, m, &paths, &to_trace));
    if let Some(traced) = &traced {
        tally.rays += to_trace.iter().filter(|&&u| u).count() as u64 * traced.len() as u64;
    }
    let vertices = ReflectorVertices {
        mesh: m,
        paths: &paths,
        hits: &hits,
        traced: traced.as_deref(),
        unresolved: &unresolved,
        on_reflector: &on_reflector,
    };
    let draws = patch_draws(&vertices, &patches, settings.resolution, eye, tally);
    let unresolved = unresolved.iter().filter(|&&u| u).count();
    tally.passes += draws.iter().map(PatchDraw::passes).sum::<u64>();
    tally.zooming_views += patches.iter().filter(|p| p.zooming.is_some()).count() as u64;
    tally.principal_up += patches.iter().filter(|p| p.principal_up).count() as u64;
    tally.unresolved += unresolved as u64;
    if top {
        let visible = paths.visible.iter().filter(|&&v| v).count();
        report(tally, m, visible, unresolved, &patches, settings);
    }
    if let Some(size) = settings.markers {
        for (c, (channel, h)) in paths.channels.iter().zip(&hits).enumerate() {
            plan.balls.extend(marker_balls(
                size,
                c as u32,
                m,
                &paths.visible,
                &channel.exits,
                h,
            ));
        }
    }
    plan.reflectors.push(ReflectorDraw {
        mesh,
        material: GpuMirrorMaterial {
            stripes: settings.markers.is_some() as u32,
            blend_traced: (settings.zooming != Zooming::Map) as u32,
            ..reflector.material
        },
        additive: reflector.additive,
        patches: draws,
    });
}

/// Step 1 for `reflector` seen from `eye`: its paths from its cache entry (`slot`, the cached
/// mode) where that is still valid for its vertices in the eye's frame (`key`), with the
/// cached patches; else traced, without patches.
pub(super) fn reflector_paths(
    p: &Shared,
    scene: &Scene,
    reflector: &Reflector,
    eye: Vec3,
    slot: Option<&(&mut Option<CachedReflector>, EyeFrame)>,
    key: Option<&Vec<Vec3>>,
    tally: &mut Tally,
) -> (MeshPaths, Option<Vec<Patch>>) {
    let (mesh, interaction) = (reflector.mesh, &reflector.interaction);
    let reused = slot
        .zip(key)
        .and_then(|((slot, frame), key)| reuse(slot, frame, key, interaction));
    match reused {
        Some((paths, patches)) => {
            tally.cache_hits += 1;
            (paths, Some(patches))
        }
        None => {
            let paths = trace_paths(scene, p.accel, mesh, eye, interaction);
            tally.rays += paths.rays;
            (paths, None)
        }
    }
}

/// The cache entry of a reflector whose `paths` and `patches` were just computed: them
/// carried into the eye's `frame`, valid while its vertices there (`key`) and its
/// `interaction` stay unchanged.
pub(super) fn cache_entry(
    frame: &EyeFrame,
    key: Vec<Vec3>,
    interaction: &Interaction,
    paths: &MeshPaths,
    patches: &[Patch],
) -> CachedReflector {
    let (paths, patches) = map_state(
        paths,
        patches,
        |q| frame.point_to_local(q),
        |v| frame.vector_to_local(v),
    );
    CachedReflector {
        key,
        interaction: interaction.clone(),
        paths,
        patches,
    }
}

/// The vertices whose P some patch's map cannot show: behind a forward view's viewpoint (the
/// zooming region, where no zooming view is drawn); in a zooming view, too near its
/// viewpoint's plane for its map to hold (at the rays' convergence), or on a surface the
/// raster leaves black (a mirror or lens: a zooming view draws no nested level). Unless `zooming=map` they take the radiance ray traced along their exit segment
/// instead of the map's, per channel.
pub(super) fn unresolved_vertices(
    m: &specula_scene::Mesh,
    visible: &[bool],
    hits: &[Vec<Vec3>],
    drawn: &[Vec<bool>],
    patches: &[Patch],
) -> Vec<bool> {
    let mut unresolved = vec![false; m.positions.len()];
    for patch in patches {
        let reversed = patch.basis.reversed();
        let unshown = |p: Vec3, drawn: bool| match &patch.zooming {
            None => patch.basis.local(p).z <= 0.0,
            Some(zooming) => {
                let q = reversed.local(p);
                let (x, y) = (q.x.abs() / q.z.abs(), q.y.abs() / q.z.abs());
                let before_near = q.z > 0.0 && q.z < zooming.near;
                let shown = x <= zooming.tan_x && y <= zooming.tan_y && drawn && !before_near;
                !shown
            }
        };
        for &t in &patch.triangles {
            for i in m.triangles[t as usize] {
                let i = i as usize;
                unresolved[i] |=
                    visible[i] && hits.iter().zip(drawn).any(|(h, d)| unshown(h[i], d[i]));
            }
        }
    }
    unresolved
}

/// Per channel, the radiance traced along each `unresolved` vertex's exit segment (zero for
/// the others).
pub(super) fn trace_unresolved(
    p: &Shared,
    scene: &Scene,
    m: &specula_scene::Mesh,
    paths: &MeshPaths,
    unresolved: &[bool],
) -> Vec<Vec<Vec3>> {
    let tracer = specula_trace::reference::Tracer {
        scene,
        accel: p.accel,
        max_depth: TRACED_DEPTH,
    };
    let dispersive = paths.channels.len() == 3;
    paths
        .channels
        .iter()
        .enumerate()
        .map(|(c, channel)| {
            (0..m.positions.len())
                .into_par_iter()
                .map(|i| {
                    if !unresolved[i] {
                        return Vec3::ZERO;
                    }
                    let exit = channel.exits[i];
                    let ray = specula_trace::Ray {
                        origin: exit.origin,
                        dir: exit.dir,
                    };
                    tracer.radiance(&ray, 1, dispersive.then_some(c))
                })
                .collect()
        })
        .collect()
}

/// What each vertex of a reflector brings to its patches' draws.
pub(super) struct ReflectorVertices<'a> {
    pub(super) mesh: &'a specula_scene::Mesh,
    pub(super) paths: &'a MeshPaths,
    /// Per channel, where each vertex's exit segment hits the scene (P).
    pub(super) hits: &'a [Vec<Vec3>],
    /// Per channel, the radiance traced for each unresolved vertex and each vertex on
    /// another reflector (not `zooming=map`).
    pub(super) traced: Option<&'a [Vec<Vec3>]>,
    pub(super) unresolved: &'a [bool],
    /// Whether each vertex's P lies on another mirror or lens.
    pub(super) on_reflector: &'a [bool],
}

/// Each patch's map camera and mirror vertices per channel. The reflector's map budget
/// (`resolution` texels high) is shared by its patches in proportion to how much of the view
/// from `eye` each covers.
pub(super) fn patch_draws(
    vertices: &ReflectorVertices,
    patches: &[Patch],
    resolution: u32,
    eye: Vec3,
    tally: &mut Tally,
) -> Vec<PatchDraw> {
    let m = vertices.mesh;
    let solid_angles: Vec<f32> = patches
        .iter()
        .map(|patch| solid_angle(m, &patch.triangles, eye))
        .collect();
    let total_solid_angle = solid_angles.iter().sum::<f32>().max(f32::MIN_POSITIVE);
    patches
        .iter()
        .zip(&solid_angles)
        .map(|(patch, &solid_angle)| {
            let share = (solid_angle / total_solid_angle).clamp(0.0, 1.0);
            let height = ((resolution as f32 * share.sqrt()).round() as u32)
                .clamp(MIN_MAP_TEXELS.min(resolution), resolution);
            let (camera, fill) = patch_cameras(patch, height);
            // A zooming view's P beyond its viewpoint projects through it, where the map holds
            // the forward view; elsewhere an unresolved vertex's P is mirrored to the front
            // for the blend with its traced radiance.
            let mirror_behind = vertices.traced.is_some() && patch.zooming.is_none();
            let channels = vertices
                .paths
                .channels
                .iter()
                .zip(vertices.hits)
                .enumerate()
                .map(|(c, (channel, h))| {
                    patch
                        .triangles
                        .iter()
                        .flat_map(|&t| m.triangles[t as usize])
                        .map(|i| {
                            let i = i as usize;
                            let traced = vertices.traced.map_or(Vec3::ZERO, |t| t[c][i]);
                            MirrorVertex {
                                position: m.positions[i].to_array(),
                                normal: m.normals[i].to_array(),
                                uv: if patch.zooming.is_some() && vertices.unresolved[i] {
                                    // Its P may lie on the viewpoint's plane: its line's
                                    // direction, through its exit point, stays in the map.
                                    map_uv(&camera, channel.exits[i].origin, false)
                                } else {
                                    map_uv(&camera, h[i], mirror_behind)
                                },
                                weight: channel.weights[i],
                                unresolved: vertices.unresolved[i] as u32 as f32,
                                traced: traced.to_array(),
                            }
                        })
                        .collect()
                })
                .collect();
            let reflector_corners = patch
                .triangles
                .iter()
                .flat_map(|&t| m.triangles[t as usize])
                .map(|i| vertices.on_reflector[i as usize])
                .collect();
            let draw = PatchDraw {
                camera,
                fill,
                channels,
                reflector_corners,
            };
            tally.map_texels += draw.texels();
            draw
        })
        .collect()
}

/// The top level's warnings about one reflector.
pub(super) fn report(
    tally: &mut Tally,
    mesh: &specula_scene::Mesh,
    visible: usize,
    unresolved: usize,
    patches: &[Patch],
    settings: &PlanSettings,
) {
    let limits = &settings.limits;
    if let Some(fallback) = patches.iter().find_map(|p| p.fallback.clone()) {
        tally.warnings.push(fallback);
    }
    if visible > 0 && visible < MIN_VISIBLE_VERTICES {
        tally.warnings.push(format!(
            "pvrr: mirror '{}' shows only {visible} vertices; between vertices the reflection is a linear warp, so tessellate it more finely (the paper's door mirror has 49)",
            mesh.name
        ));
    }
    if unresolved > 0 {
        let message = match settings.zooming {
            Zooming::View => format!(
                "{unresolved} vertices see a point their patch's map cannot show (behind its viewpoint where too few are for a zooming view, at their rays' convergence, or a mirror or lens seen from a zooming view); they show their ray-traced radiance instead"
            ),
            Zooming::Traced => format!(
                "{unresolved} vertices see a point between the surface and their rays' convergence (a concave mirror's zooming region), which no forward view shows; they show their ray-traced radiance instead (zooming=traced)"
            ),
            Zooming::Map => format!(
                "{unresolved} vertices see a point between the surface and their rays' convergence (a concave mirror's zooming region), which no forward view shows; they show the map where their line through the viewpoint meets it, as the paper's algorithm does (zooming=map)"
            ),
        };
        tally.warnings.push(format!(
            "pvrr: mirror '{}': {message} (striped magenta with markers=true)",
            mesh.name
        ));
    }
    let wide = patches
        .iter()
        .filter(|p| p.extents.fov_deg() > limits.max_fov_deg)
        .count();
    if wide > 0 {
        tally.warnings.push(format!(
            "pvrr: mirror '{}': {wide} of {} patches still span more than max_fov = {}° (single triangles, or the max_patches limit reached)",
            mesh.name,
            patches.len(),
            limits.max_fov_deg
        ));
    }
}

/// The levels below `level` (planned with `settings`), `depth` levels deep,
/// within `budget`: each outer patch in turn, largest map first, gets a level of its own if
/// what is left covers it (its per-vertex rays estimated before they are traced), else none
/// (and `tally` counts the cut). Nested levels share one `max_patches` per reflector across the outer level's patches
/// (three mirrors seeing each other took 143,053 patches, 264 s at 96 × 72, without it).
#[allow(clippy::too_many_arguments)]
pub(super) fn plan_tree(
    p: &Shared,
    settings: &PlanSettings,
    scene: &Scene,
    level: LevelPlan,
    depth: u32,
    budget: &mut FrameBudget,
    tally: &mut Tally,
) -> PlanTree {
    if depth <= 1 {
        return PlanTree {
            level,
            inner: Vec::new(),
        };
    }
    let outer_patches = level.passes().max(1);
    let inner_settings = PlanSettings {
        limits: PatchLimits {
            max_patches: (settings.limits.max_patches / outer_patches as usize).max(1),
            ..settings.limits
        },
        ..*settings
    };
    // The largest maps first: where the budget runs out, the reflections seen in the largest
    // parts of the picture are kept.
    let mut order: Vec<(usize, usize, u64)> =
        level
            .reflectors
            .iter()
            .enumerate()
            .flat_map(|(r, reflector)| {
                reflector.patches.iter().enumerate().map(move |(i, patch)| {
                    (r, i, (patch.camera.width * patch.camera.height) as u64)
                })
            })
            .collect();
    order.sort_by_key(|&(r, i, texels)| (std::cmp::Reverse(texels), r, i));
    let mut inner: Vec<Vec<Option<PlanTree>>> = level
        .reflectors
        .iter()
        .map(|reflector| reflector.patches.iter().map(|_| None).collect())
        .collect();
    for (r, i, _) in order {
        let (reflector, patch) = (&level.reflectors[r], &level.reflectors[r].patches[i]);
        // A zooming view shows other reflectors as the scene raster draws them: a nested level
        // drawn into it would need the reversed depth test in its 2nd pass too. A patch none
        // of whose hits lies on another reflector needs none: its map shows no reflector at
        // its vertices (on the pair of a mirror and a glass sphere, the budget went to such
        // patches and the glass seen in the mirror stayed black).
        if patch.fill.is_some() || !patch.sees_reflectors() {
            continue;
        }
        let eye = Vec3::from_array(patch.camera.eye_world);
        let hidden = Some(reflector.mesh);
        // The rays a level from here would trace: every other reflector's vertices, once per
        // path (a lower bound: lenses trace a path per colour).
        let rays: u64 = p
            .reflectors
            .iter()
            .filter(|other| Some(other.mesh) != hidden && !other.additive)
            .map(|other| scene.meshes[other.mesh].positions.len() as u64)
            .sum();
        if !budget.covers(1, (MIN_MAP_TEXELS * MIN_MAP_TEXELS) as u64, rays) {
            tally.budget_cuts += 1;
            continue;
        }
        // What the outer map shows of a reflector needs no finer map than the outer one.
        let here = PlanSettings {
            resolution: (patch.camera.height as u32).clamp(MIN_MAP_TEXELS, settings.resolution),
            ..inner_settings
        };
        let rays_before = tally.rays;
        let planned = plan_level(p, &here, scene, eye, hidden, None, tally, false);
        let rays = tally.rays - rays_before;
        if !budget.covers(planned.passes(), planned.texels(), rays) {
            // Planned, not drawn: its rays were traced (and count), its passes are not made.
            // What is left cannot be trusted to cover the next one either (the zooming
            // region's traced vertices are known only once traced): the budget is spent.
            tally.passes -= planned.passes();
            tally.zooming_views -= planned.zooming_views();
            tally.map_texels -= planned.texels();
            tally.budget_cuts += 1;
            *budget = FrameBudget {
                patches: 0,
                texels: 0,
                rays: 0,
            };
            continue;
        }
        budget.spend(planned.passes(), planned.texels(), rays);
        tally.nested_passes += planned.passes();
        tally.nested_texels += planned.texels();
        inner[r][i] = Some(plan_tree(
            p,
            &here,
            scene,
            planned,
            depth - 1,
            budget,
            tally,
        ));
    }
    PlanTree { level, inner }
}

/// Where `tree` plans no nested level under a patch (the frame budget, the deepest level, or
/// `depth=1`), the patch's corners whose P lies on another reflector take their traced
/// radiance, not the black the map holds there. Returns how many corners.
pub(super) fn trace_where_no_nested_level(tree: &mut PlanTree) -> u64 {
    let mut corners = 0;
    for (r, reflector) in tree.level.reflectors.iter_mut().enumerate() {
        for (i, patch) in reflector.patches.iter_mut().enumerate() {
            match tree
                .inner
                .get_mut(r)
                .and_then(|patches| patches[i].as_mut())
            {
                Some(inner) => corners += trace_where_no_nested_level(inner),
                None => corners += patch.trace_reflector_corners(),
            }
        }
    }
    corners
}
