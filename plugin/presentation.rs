//! Windowed or headless: one switch for examples and render tests.
//!
//! With a display (`DISPLAY` or `WAYLAND_DISPLAY` set) an app opens a
//! window. Without one it renders offscreen into an image, captures PNG
//! screenshots at chosen frames, prints where they went and exits — so every
//! example also runs in CI and on servers, on a CPU Vulkan driver.

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
    /// Give up (exit with an error) after this many frames.
    pub max_frames: u32,
}

impl HeadlessConfig {
    /// 960×540, screenshots at frames 4 and 12 into `screenshots/`.
    #[must_use]
    pub fn new(stem: impl Into<String>) -> Self {
        Self {
            width: 960,
            height: 540,
            capture_frames: vec![4, 12],
            output_dir: Some(PathBuf::from("screenshots")),
            stem: stem.into(),
            max_frames: 120,
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
#[derive(Resource, Clone, Default)]
pub struct CapturedFrames(Arc<Mutex<Vec<Image>>>);

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

#[derive(Resource, Clone)]
struct HeadlessState {
    config: HeadlessConfig,
    target: Option<Handle<Image>>,
    frame: u32,
}

impl Plugin for HeadlessCapturePlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins(ScheduleRunnerPlugin::run_loop(Duration::ZERO))
            .insert_resource(HeadlessState {
                config: self.config.clone(),
                target: None,
                frame: 0,
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

fn request_screenshots(mut state: ResMut<HeadlessState>, mut commands: Commands) {
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
    commands.spawn(Screenshot::image(target.clone())).observe(
        move |captured: On<ScreenshotCaptured>, frames: Res<CapturedFrames>| {
            frames.push(captured.image.clone());
            if let Some(path) = &path {
                save_png(&captured.image, path);
            }
        },
    );
}

fn save_png(image: &Image, path: &std::path::Path) {
    if let Some(dir) = path.parent() {
        let _ = std::fs::create_dir_all(dir);
    }
    match image.clone().try_into_dynamic() {
        Ok(dynamic) => match dynamic.to_rgb8().save(path) {
            Ok(()) => println!("headless: wrote screenshot {}", path.display()),
            Err(e) => eprintln!("headless: cannot write {}: {e}", path.display()),
        },
        Err(e) => eprintln!("headless: cannot convert screenshot: {e:?}"),
    }
}

fn exit_when_done(
    state: Res<HeadlessState>,
    frames: Res<CapturedFrames>,
    mut exit: MessageWriter<AppExit>,
) {
    let wanted = state.config.capture_frames.len();
    if frames.images().len() >= wanted {
        exit.write(AppExit::Success);
    } else if state.frame >= state.config.max_frames {
        eprintln!(
            "headless: only {} of {wanted} screenshots after {} frames",
            frames.images().len(),
            state.frame
        );
        exit.write(AppExit::error());
    }
}
