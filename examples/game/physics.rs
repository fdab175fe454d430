//! The game's side of its physics: which engine runs it, and the
//! [`Body`] that the game reads and steers whatever the engine.

use bevy::prelude::*;

use super::{PLAYER_LENGTH, PLAYER_RADIUS};

/// The ground probe: a sphere of this radius cast down from the capsule's
/// centre, up to `PROBE_REACH`; the player stands on what it hits within
/// `GROUND_REACH` (just below the capsule's bottom).
pub const PROBE_RADIUS: f32 = PLAYER_RADIUS * 0.9;
pub const PROBE_REACH: f32 = PLAYER_LENGTH / 2.0 + 0.2;
pub const GROUND_REACH: f32 = PLAYER_LENGTH / 2.0 + 0.1;

/// The physics engine that runs the game.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PhysicsEngine {
    Avian,
    Rapier,
}

impl PhysicsEngine {
    /// `--physics NAME` (or `--physics=NAME`), else `CHISEL_PHYSICS`, else
    /// avian3d.
    pub fn from_args_or_env() -> Result<Self, String> {
        let args: Vec<String> = std::env::args().skip(1).collect();
        let from_args = args
            .iter()
            .enumerate()
            .find_map(|(k, arg)| match arg.as_str() {
                "--physics" => Some(args.get(k + 1).cloned().unwrap_or_default()),
                _ => arg.strip_prefix("--physics=").map(str::to_owned),
            });
        match from_args
            .or_else(|| std::env::var("CHISEL_PHYSICS").ok())
            .as_deref()
        {
            None | Some("avian") => Ok(Self::Avian),
            Some("rapier") => Ok(Self::Rapier),
            Some(other) => Err(format!(
                "unknown physics engine {other:?}: `avian` (the default) or `rapier`"
            )),
        }
    }

    /// The engine's plugins, the player's body and the systems that copy
    /// [`Body`] to and from the simulation.
    pub fn add_to(self, app: &mut App, headless: bool) {
        match self {
            Self::Avian => super::avian::add_physics(app, headless),
            Self::Rapier => super::rapier::add_physics(app, headless),
        }
    }
}

/// The player's body as the game sees it, whatever the engine: the
/// engine's module fills it in from the simulation before `Update` and
/// hands `velocity` back to the simulation after it.
#[derive(Component, Default)]
pub struct Body {
    pub velocity: Vec3,
    /// The ground probe touches something within [`GROUND_REACH`].
    pub grounded: bool,
    /// What the capsule touches.
    pub touching: Vec<Entity>,
}

/// Systems that run after the physics step has written the bodies'
/// transforms back, and before transforms propagate (the engine's module
/// orders it after its writeback).
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct AfterPhysics;
