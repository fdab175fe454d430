//! Windowed or headless: one switch for examples and render tests.
//!
//! With a display (`DISPLAY` or `WAYLAND_DISPLAY` set, and
//! `CHISEL_HEADLESS` not set) an app opens a window. Without one it
//! renders offscreen into an image, captures PNG screenshots at chosen
//! frames, prints where they went and exits — so every example also runs
//! in CI and on servers, on a CPU Vulkan driver.
//!
//! Every capture is checked for content: a frame whose pixels are nearly
//! all one colour (the clear colour of a scene that failed to draw, or an
//! image the renderer never wrote) fails the run ([`foreground_fraction`],
//! [`HeadlessConfig::min_foreground`]). A scene that needs time before it
//! is worth capturing (carving, sampling) holds the frame count with
//! [`HoldCaptures`].

use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use bevy::app::ScheduleRunnerPlugin;
use bevy::asset::RenderAssetUsages;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::render_resource::{Extent3d, TextureDimension, TextureFormat, TextureUsages};
use bevy::render::view::screenshot::{Screenshot, ScreenshotCaptured};
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;

/// How an app presents its frames.
#[derive(Clone, Debug)]
pub enum Presentation {
    /// An ordinary window on the display.
    Window,
    /// Offscreen rendering with screenshots, then exit.
    Headless(HeadlessConfig),
}

/// Settings of a headless run.
#[derive(Clone, Debug)]
pub struct HeadlessConfig {
    /// Width of the offscreen target in pixels.
    pub width: u32,
    /// Height of the offscreen target in pixels.
    pub height: u32,
    /// Frames at which screenshots are taken (1-based frame numbers).
    pub capture_frames: Vec<u32>,
    /// Directory for the PNG files; `None` keeps the images in memory only
    /// (see [`CapturedFrames`]).
    pub output_dir: Option<PathBuf>,
    /// File name stem: screenshots are `{stem}-{frame:04}.png`.
    pub stem: String,
    /// Give up (exit with an error) after this many frames in all,
    /// counting frames under [`HoldCaptures`].
    pub max_frames: u32,
    /// Smallest fraction of every capture that must differ from the
    /// frame's background (see [`foreground_fraction`]); a capture with
    /// less fails the run. `0.0` turns the check off.
    pub min_foreground: f32,
}

impl HeadlessConfig {
    /// 960×540, screenshots at frames 4 and 12 into `screenshots/`, each
    /// at least 10% foreground.
    #[must_use]
    pub fn new(stem: impl Into<String>) -> Self {
        Self {
            width: 960,
            height: 540,
            capture_frames: vec![4, 12],
            output_dir: Some(PathBuf::from("screenshots")),
            stem: stem.into(),
            max_frames: 120,
            min_foreground: 0.1,
        }
    }
}

/// True when a window can be opened: `DISPLAY` or `WAYLAND_DISPLAY` is set
/// and `CHISEL_HEADLESS` is not.
#[must_use]
pub fn display_available() -> bool {
    let set = |name: &str| std::env::var_os(name).is_some_and(|v| !v.is_empty());
    !set("CHISEL_HEADLESS") && (set("DISPLAY") || set("WAYLAND_DISPLAY"))
}

impl Presentation {
    /// A window when a display is available, headless screenshots named
    /// after `stem` otherwise.
    #[must_use]
    pub fn detect(stem: &str) -> Self {
        if display_available() {
            Presentation::Window
        } else {
            Presentation::Headless(HeadlessConfig::new(stem))
        }
    }

    /// Adds Bevy's `DefaultPlugins` configured for this presentation (and,
    /// when headless, the [`HeadlessCapturePlugin`]). Returns the handle to
    /// the captured images, empty in windowed mode.
    pub fn add_default_plugins(&self, app: &mut App, title: &str) -> CapturedFrames {
        let frames = CapturedFrames::default();
        match self {
            Presentation::Window => {
                app.add_plugins(DefaultPlugins.set(WindowPlugin {
                    primary_window: Some(Window {
                        title: title.to_owned(),
                        ..default()
                    }),
                    ..default()
                }));
            }
            Presentation::Headless(config) => {
                app.add_plugins((
                    DefaultPlugins
                        .set(WindowPlugin {
                            primary_window: None,
                            exit_condition: ExitCondition::DontExit,
                            ..default()
                        })
                        .set(RenderPlugin {
                            synchronous_pipeline_compilation: true,
                            ..default()
                        })
                        .disable::<WinitPlugin>(),
                    HeadlessCapturePlugin {
                        config: config.clone(),
                        frames: frames.clone(),
                    },
                ));
            }
        }
        frames
    }
}

/// Images captured by a headless run, shared with whoever started it (a test
/// reads pixels from here after `App::run` returns).
#[derive(Resource, Reflect, Clone, Default)]
#[reflect(Resource)]
pub struct CapturedFrames(#[reflect(ignore)] Arc<Mutex<Vec<Image>>>);

impl CapturedFrames {
    /// The images captured so far, in capture order.
    #[must_use]
    pub fn images(&self) -> Vec<Image> {
        self.0.lock().map(|v| v.clone()).unwrap_or_default()
    }

    fn push(&self, image: Image) -> usize {
        match self.0.lock() {
            Ok(mut v) => {
                v.push(image);
                v.len()
            }
            Err(_) => 0,
        }
    }
}

/// Renders every camera into an offscreen image, captures screenshots at
/// the configured frames, writes them as PNG and exits when all are in.
pub struct HeadlessCapturePlugin {
    /// What to capture and where.
    pub config: HeadlessConfig,
    /// Where captured images are collected.
    pub frames: CapturedFrames,
}

/// While this resource is present and `true`, a headless run does not
/// count frames towards [`HeadlessConfig::capture_frames`]: a scene sets it
/// while it is still carving or sampling, so that the screenshots show the
/// finished state. [`HeadlessConfig::max_frames`] still counts every frame.
/// Ignored in a window.
#[derive(Resource, Reflect, Clone, Copy, Debug, Default, PartialEq, Eq)]
#[reflect(Resource, Default)]
pub struct HoldCaptures(pub bool);

#[derive(Resource, Clone)]
struct HeadlessState {
    config: HeadlessConfig,
    target: Option<Handle<Image>>,
    /// Frames counted towards the captures.
    frame: u32,
    /// Every frame.
    total: u32,
    /// Captures that failed the content check.
    failures: Vec<String>,
}

impl Plugin for HeadlessCapturePlugin {
    fn build(&self, app: &mut App) {
        app.register_type::<CapturedFrames>()
            .register_type::<HoldCaptures>()
            .add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
            .insert_resource(HeadlessState {
                config: self.config.clone(),
                target: None,
                frame: 0,
                total: 0,
                failures: Vec::new(),
            })
            .insert_resource(self.frames.clone())
            .add_systems(PreStartup, create_offscreen_target)
            .add_systems(Last, (request_screenshots, exit_when_done).chain())
            .add_observer(redirect_cameras_offscreen);
    }
}

fn create_offscreen_target(mut state: ResMut<HeadlessState>, mut images: ResMut<Assets<Image>>) {
    let size = Extent3d {
        width: state.config.width,
        height: state.config.height,
        depth_or_array_layers: 1,
    };
    let mut image = Image::new_uninit(
        size,
        TextureDimension::D2,
        TextureFormat::Rgba8UnormSrgb,
        RenderAssetUsages::RENDER_WORLD,
    );
    image.texture_descriptor.usage |= TextureUsages::RENDER_ATTACHMENT | TextureUsages::COPY_SRC;
    state.target = Some(images.add(image));
}

/// Points every new camera at the offscreen image; the first one also draws
/// the UI (which otherwise looks for a camera on the primary window).
fn redirect_cameras_offscreen(
    add: On<Add, Camera>,
    state: Res<HeadlessState>,
    ui_cameras: Query<(), With<IsDefaultUiCamera>>,
    mut commands: Commands,
) {
    if let Some(target) = &state.target {
        let mut camera = commands.entity(add.entity);
        camera.insert(RenderTarget::Image(target.clone().into()));
        if ui_cameras.is_empty() {
            camera.insert(IsDefaultUiCamera);
        }
    }
}

fn request_screenshots(
    mut state: ResMut<HeadlessState>,
    hold: Option<Res<HoldCaptures>>,
    mut commands: Commands,
) {
    state.total += 1;
    if hold.is_some_and(|h| h.0) {
        return;
    }
    state.frame += 1;
    let frame = state.frame;
    let (Some(target), true) = (&state.target, state.config.capture_frames.contains(&frame)) else {
        return;
    };
    let path = state
        .config
        .output_dir
        .as_ref()
        .map(|dir| dir.join(format!("{}-{frame:04}.png", state.config.stem)));
    let name = path.as_ref().map_or_else(
        || format!("{} frame {frame}", state.config.stem),
        |p| p.display().to_string(),
    );
    commands.spawn(Screenshot::image(target.clone())).observe(
        move |captured: On<ScreenshotCaptured>,
              frames: Res<CapturedFrames>,
              mut state: ResMut<HeadlessState>| {
            frames.push(captured.image.clone());
            let rgb = match captured.image.clone().try_into_dynamic() {
                Ok(dynamic) => dynamic.to_rgb8(),
                Err(e) => {
                    state
                        .failures
                        .push(format!("{name}: cannot convert the capture: {e:?}"));
                    return;
                }
            };
            let foreground = foreground_fraction(&rgb, BACKGROUND_TOLERANCE);
            if let Some(path) = &path {
                save_png(&rgb, path, foreground);
            }
            let min = state.config.min_foreground;
            if foreground < min {
                state.failures.push(format!(
                    "{name}: only {:.1}% of the frame differs from its background \
                     (at least {:.1}% expected): the scene did not draw",
                    100.0 * foreground,
                    100.0 * min
                ));
            }
        },
    );
}

fn save_png(rgb: &image::RgbImage, path: &std::path::Path, foreground: f32) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    match rgb.save(path) {
        Ok(()) => println!(
            "headless: wrote screenshot {} ({:.0}% foreground)",
            path.display(),
            100.0 * foreground
        ),
        Err(e) => eprintln!("headless: cannot write {}: {e}", path.display()),
    }
}

/// How far (per channel, 0–255) a pixel may stray from the background
/// colour and still count as background: dithering moves the clear colour
/// by a step or two.
pub const BACKGROUND_TOLERANCE: u8 = 8;

/// The fraction of `image`'s pixels that differ from its background — its
/// most common colour — by more than `tolerance` in some channel.
///
/// A frame in which nothing was drawn is one colour (the clear colour, or
/// whatever the target held) up to dithering, so its fraction is near 0;
/// text overlays add a few percent. Scenery that fills much of the frame
/// gives a large fraction even where one flat face is its most common
/// colour, since the sky then counts as foreground.
#[must_use]
pub fn foreground_fraction(image: &image::RgbImage, tolerance: u8) -> f32 {
    let pixels = image.pixels().count();
    if pixels == 0 {
        return 0.0;
    }
    let mut counts: std::collections::HashMap<[u8; 3], u32> = std::collections::HashMap::new();
    for p in image.pixels() {
        *counts.entry(p.0).or_default() += 1;
    }
    let Some(background) = counts
        .iter()
        .max_by_key(|&(colour, n)| (*n, *colour))
        .map(|(colour, _)| *colour)
    else {
        return 0.0;
    };
    let differs = |p: &image::Rgb<u8>| {
        p.0.iter()
            .zip(background)
            .any(|(&a, b)| a.abs_diff(b) > tolerance)
    };
    image.pixels().filter(|p| differs(p)).count() as f32 / pixels as f32
}

fn exit_when_done(
    state: Res<HeadlessState>,
    frames: Res<CapturedFrames>,
    mut exit: MessageWriter<AppExit>,
) {
    let wanted = state.config.capture_frames.len();
    if frames.images().len() >= wanted {
        if state.failures.is_empty() {
            exit.write(AppExit::Success);
        } else {
            for failure in &state.failures {
                eprintln!("headless: {failure}");
            }
            exit.write(AppExit::error());
        }
    } else if state.total >= state.config.max_frames {
        eprintln!(
            "headless: only {} of {wanted} screenshots after {} frames",
            frames.images().len(),
            state.total
        );
        exit.write(AppExit::error());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::{Rgb, RgbImage};

    #[test]
    fn an_empty_frame_has_no_foreground() {
        // The clear colour, dithered by ±1.
        let sky = RgbImage::from_fn(64, 48, |x, y| {
            let d = ((x + y) % 3) as u8;
            Rgb([134 + d, 173 - d, 214])
        });
        assert!(foreground_fraction(&sky, BACKGROUND_TOLERANCE) < 0.001);
        // A never-written target.
        let black = RgbImage::new(64, 48);
        assert_eq!(foreground_fraction(&black, BACKGROUND_TOLERANCE), 0.0);
    }

    #[test]
    fn scenery_counts_even_when_one_face_dominates() {
        // Top 40% sky, bottom 60% one flat face of a block.
        let image = RgbImage::from_fn(100, 100, |_, y| {
            if y < 40 {
                Rgb([134, 173, 214])
            } else {
                Rgb([90, 140, 60])
            }
        });
        let f = foreground_fraction(&image, BACKGROUND_TOLERANCE);
        assert!((f - 0.4).abs() < 1e-6, "{f}");
        // A line of text on the sky is not scenery.
        let text = RgbImage::from_fn(100, 100, |x, y| {
            if y < 3 && x % 2 == 0 {
                Rgb([255, 255, 255])
            } else {
                Rgb([134, 173, 214])
            }
        });
        assert!(foreground_fraction(&text, BACKGROUND_TOLERANCE) < 0.1);
    }
}
