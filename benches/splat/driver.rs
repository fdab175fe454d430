//! The sequence of a scene's steps and the system that drives it: each
//! step's settings, camera MSAA and visibility, the pass measurements told
//! apart by what they drew, and the read-backs (see the docs of `splat.rs`).

use super::*;

#[derive(Resource)]
pub(super) struct Driver {
    pub(super) steps: Vec<Step>,
    pub(super) step: usize,
    /// Frames since the current step began (1 on its first frame).
    pub(super) frame: u32,
    /// Pass measurements of the current step's drawing taken in this step.
    pub(super) taken: u32,
    pub(super) target: Handle<Image>,
    /// Splats of the prop: tells the modes apart by vertex invocations.
    pub(super) splat_count: u32,
    /// Time of the last diagnostics measurement consumed.
    pub(super) last_measurement: Option<Instant>,
    /// Variants measured once, with their MSAA samples: the first frame of
    /// each also compiles lavapipe's shader variants and is not recorded.
    pub(super) seen: Vec<(Variant, u32)>,
    /// The MSAA samples of the latest timing step that drew each variant:
    /// a late measurement of a variant is of that step (steps of the same
    /// variant are never adjacent, and a measurement lags less than a
    /// step).
    pub(super) samples_of: HashMap<Variant, u32>,
    /// The read-back of the current step has arrived.
    pub(super) read_done: Arc<Mutex<bool>>,
    pub(super) reader: Option<Entity>,
    pub(super) total_frames: u32,
}

impl Driver {
    /// The variant that drew `vertices` vertex invocations: diagnostics
    /// arrive a few frames late, so they are told apart by what they drew.
    fn variant_of(&self, vertices: f64) -> Option<Variant> {
        [
            Variant::Boxes,
            Variant::OpenBoxes,
            Variant::Quads,
            Variant::Global,
        ]
        .into_iter()
        .find(|v| v.vertices(self.splat_count).total_cmp(&vertices).is_eq())
    }
}

/// The steps of one scene: `ROUNDS` timing rounds (with the boxes and the
/// empty frame also at `msaa` samples where `msaa > 1`, after the global
/// pass so that no two steps of one variant are adjacent), then the
/// read-backs, at one sample. `msaa_only`: only the boxes and the empty
/// frame are timed, and nothing is read back.
pub(super) fn steps(
    splat_frames: u32,
    global_frames: u32,
    msaa: u32,
    msaa_only: bool,
) -> Vec<Step> {
    let mut steps = Vec::new();
    let multisampled = if msaa > 1 { splat_frames } else { 0 };
    let others = if msaa_only { 0 } else { splat_frames };
    let global_frames = if msaa_only { 0 } else { global_frames };
    for _ in 0..ROUNDS {
        for (draw, frames, samples) in [
            (Draw::Prop(Variant::Boxes), splat_frames, 1),
            (Draw::Prop(Variant::OpenBoxes), others, 1),
            (Draw::Prop(Variant::Quads), others, 1),
            (Draw::Empty, splat_frames, 1),
            (Draw::Prop(Variant::Global), global_frames, 1),
            (Draw::Prop(Variant::Boxes), multisampled, msaa),
            (Draw::Empty, multisampled, msaa),
        ] {
            if frames > 0 {
                steps.push(Step::Time {
                    draw,
                    frames,
                    samples,
                });
            }
        }
    }
    if msaa_only {
        return steps;
    }
    for (variant, output) in [
        (Variant::Boxes, SplatOutput::QuadricIds),
        (Variant::OpenBoxes, SplatOutput::QuadricIds),
        (Variant::UnculledBoxes, SplatOutput::QuadricIds),
        (Variant::SphereBoxes, SplatOutput::QuadricIds),
        (Variant::Boxes, SplatOutput::Overdraw),
        (Variant::SphereBoxes, SplatOutput::Overdraw),
        (Variant::Boxes, SplatOutput::DepthTestedOverdraw),
        (Variant::SphereBoxes, SplatOutput::DepthTestedOverdraw),
        (Variant::UnculledBoxes, SplatOutput::Overdraw),
        (Variant::OpenBoxes, SplatOutput::Overdraw),
        (Variant::Quads, SplatOutput::Overdraw),
        (Variant::Global, SplatOutput::Overdraw),
    ] {
        if variant == Variant::Global && global_frames == 0 {
            continue;
        }
        steps.push(Step::Read { variant, output });
    }
    steps
}

/// The latest value of the pass diagnostic ending in `field`.
fn pass_diagnostic(store: &DiagnosticsStore, field: &str) -> Option<(Instant, f64)> {
    let suffix = format!("chisel_splat_pass/{field}");
    store
        .iter()
        .find(|d| d.path().as_str().ends_with(&suffix))
        .and_then(|d| d.measurement())
        .map(|m| (m.time, m.value))
}

/// Marks the prop whose splats are boxes around their spheres
/// ([`Variant::SphereBoxes`]).
#[derive(Component)]
pub(super) struct SphereProp;

/// Applies the settings, camera MSAA and visibility of `step`.
fn begin_step(
    step: Step,
    settings: &mut SplatSettings,
    props: &mut Query<(&mut Visibility, Has<SphereProp>), With<PropSplats>>,
    cameras: &mut Query<&mut Msaa, With<Camera>>,
) {
    let (variant, output, visible, samples) = match step {
        Step::Time {
            draw: Draw::Prop(variant),
            samples,
            ..
        } => (variant, SplatOutput::Shaded, true, samples),
        Step::Time {
            draw: Draw::Empty,
            samples,
            ..
        } => (Variant::Boxes, SplatOutput::Shaded, false, samples),
        Step::Read { variant, output } => (variant, output, true, 1),
    };
    for mut msaa in cameras {
        msaa.set_if_neq(Msaa::from_samples(samples));
    }
    settings.mode = variant.mode();
    settings.open_boxes = variant == Variant::OpenBoxes;
    settings.cull_facing_away = variant != Variant::UnculledBoxes;
    settings.output = output;
    for (mut v, sphere) in props {
        *v = if visible && sphere == (variant == Variant::SphereBoxes) {
            Visibility::Inherited
        } else {
            Visibility::Hidden
        };
    }
}

/// Reads `target` back once; `done` is set when the image is in the log
/// under `key`.
fn read_back(
    commands: &mut Commands,
    target: Handle<Image>,
    key: (Variant, SplatOutput),
    log: SharedLog,
    done: Arc<Mutex<bool>>,
) -> Entity {
    *done
        .lock()
        .unwrap_or_else(std::sync::PoisonError::into_inner) = false;
    commands
        .spawn(Readback::texture(target))
        .observe(move |read: On<ReadbackComplete>| {
            let image = Image::new(
                Extent3d {
                    width: WIDTH,
                    height: HEIGHT,
                    depth_or_array_layers: 1,
                },
                TextureDimension::D2,
                read.data.clone(),
                TextureFormat::Rgba16Float,
                RenderAssetUsages::MAIN_WORLD,
            );
            let pixels: Vec<[f32; 4]> = (0..HEIGHT)
                .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
                .map(|(x, y)| {
                    image
                        .get_color_at(x, y)
                        .map_or([f32::NAN; 4], |c| c.to_linear().to_f32_array())
                })
                .collect();
            log.with(|log| {
                log.images.entry(key).or_insert(pixels);
            });
            *done
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner) = true;
        })
        .id()
}

#[allow(clippy::too_many_arguments)]
pub(super) fn drive(
    mut driver: ResMut<Driver>,
    mut settings: ResMut<SplatSettings>,
    mut props: Query<(&mut Visibility, Has<SphereProp>), With<PropSplats>>,
    mut cameras: Query<&mut Msaa, With<Camera>>,
    store: Res<DiagnosticsStore>,
    time: Res<Time<Real>>,
    log: Res<SharedLog>,
    mut commands: Commands,
    mut exit: MessageWriter<AppExit>,
) {
    driver.total_frames += 1;
    if driver.total_frames > 5000 {
        eprintln!("splat bench: too many frames; giving up");
        exit.write(AppExit::error());
        return;
    }
    let Some(&step) = driver.steps.get(driver.step) else {
        exit.write(AppExit::Success);
        return;
    };
    driver.frame += 1;
    let frame = driver.frame;
    if frame == 1 {
        begin_step(step, &mut settings, &mut props, &mut cameras);
        if let Step::Time {
            draw: Draw::Prop(variant),
            samples,
            ..
        } = step
        {
            driver.samples_of.insert(variant, samples);
        }
        if let Step::Read { variant, .. } = step {
            driver.samples_of.insert(variant, 1);
        }
    }
    let asked = match step {
        Step::Time { frames, .. } => WARM_UP + frames,
        Step::Read { .. } => READ_SETTLE + 3,
    };
    if frame > asked + STEP_SLACK {
        eprintln!(
            "splat bench: step {} ({step:?}) still short of its measurements after {frame} \
             frames (asked for {asked}); giving up",
            driver.step
        );
        exit.write(AppExit::error());
        return;
    }
    // A new diagnostics measurement (of a frame a few frames back), and
    // the mode that drew it.
    let fresh = pass_diagnostic(&store, "vertex_shader_invocations")
        .filter(|(t, _)| Some(*t) != driver.last_measurement);
    let mut measured = fresh.and_then(|(t, vertices)| {
        driver.last_measurement = Some(t);
        driver.variant_of(vertices)
    });
    let measured_samples = measured.map(|v| driver.samples_of.get(&v).copied().unwrap_or(1));
    if let (Some(variant), Some(samples)) = (measured, measured_samples)
        && !driver.seen.contains(&(variant, samples))
    {
        driver.seen.push((variant, samples));
        measured = None;
    }
    let next = match step {
        Step::Time {
            draw,
            frames,
            samples,
        } => {
            if frame > WARM_UP {
                log.with(|log| {
                    let ms = time.delta_secs_f64() * 1e3;
                    log.frame_ms.entry((draw, samples)).or_default().push(ms);
                });
            }
            if let (Some(variant), Some(measured_samples)) = (measured, measured_samples)
                && let Some((_, ms)) = pass_diagnostic(&store, "elapsed_gpu")
            {
                log.with(|log| {
                    log.pass_ms
                        .entry((Draw::Prop(variant), measured_samples))
                        .or_default()
                        .push(ms);
                });
                if draw == Draw::Prop(variant) && measured_samples == samples {
                    driver.taken += 1;
                }
            }
            match draw {
                Draw::Prop(_) => driver.taken >= frames && frame > WARM_UP + 1,
                Draw::Empty => frame >= WARM_UP + frames,
            }
        }
        Step::Read { variant, output } => {
            // Culled and unculled boxes draw as many vertices: told apart
            // by the step, not by the measurement.
            let n = driver.splat_count;
            if frame > READ_SETTLE
                && measured.is_some_and(|m| m.vertices(n).total_cmp(&variant.vertices(n)).is_eq())
                && let Some((_, v)) = pass_diagnostic(&store, "fragment_shader_invocations")
            {
                log.with(|log| {
                    log.invocations
                        .entry((variant, output))
                        .or_default()
                        .push(v)
                });
            }
            if frame == READ_SETTLE {
                let reader = read_back(
                    &mut commands,
                    driver.target.clone(),
                    (variant, output),
                    log.clone(),
                    driver.read_done.clone(),
                );
                driver.reader = Some(reader);
            }
            let done = *driver
                .read_done
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            // A few more frames for the pipeline statistics of this output.
            let finished = done && frame > READ_SETTLE + 3;
            if finished && let Some(reader) = driver.reader.take() {
                commands.entity(reader).despawn();
            }
            finished
        }
    };
    if next {
        driver.step += 1;
        driver.frame = 0;
        driver.taken = 0;
    }
}
