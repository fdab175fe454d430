//! The one error type of the terrain plugin.

/// Everything that can go wrong when building, carving, saving or loading a
/// terrain. Each variant says what was wrong and how to fix it; none of them
/// leaves a terrain changed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum TerrainError {
    /// The exact kernel rejected the input (out-of-range or non-finite
    /// coordinates, a degenerate tool, an open mesh, …).
    #[error("{0}")]
    Kernel(chisel_bsp::Error),
    /// The tool lies entirely outside the terrain's octree cube, so the
    /// carve could not change anything.
    #[error(
        "the tool (grid box {tool_min:?} to {tool_max:?}) lies entirely outside the \
         terrain's cube; move it onto the terrain"
    )]
    OutsideTerrain {
        /// Lower corner of the tool's bounds, in grid units.
        tool_min: [i64; 3],
        /// Upper corner of the tool's bounds, in grid units.
        tool_max: [i64; 3],
    },
    /// A tool description that cannot give a solid: no pieces, a piece with
    /// fewer than four points, or a non-finite size.
    #[error("invalid tool: {reason}")]
    InvalidTool {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// A carve adds or paints a material the terrain does not know
    /// ([`super::Terrain::with_labels`]).
    #[error(
        "material label {label} is not one of the terrain's materials {known:?}; \
         declare it with Terrain::with_labels"
    )]
    UnknownLabel {
        /// The label asked for.
        label: chisel_bsp::tree::Label,
        /// The labels the terrain knows, in order.
        known: Vec<chisel_bsp::tree::Label>,
    },
    /// A carve adds or paints a material that the terrain knows but its
    /// material table (`TerrainMaterials`) has no entry for, so it would be
    /// drawn with the table's fallback.
    #[error(
        "material label {label} has no entry in the terrain's material table \
         (it has {table:?}); add one to its TerrainMaterials"
    )]
    NoMaterial {
        /// The label asked for.
        label: chisel_bsp::tree::Label,
        /// The labels the table has materials for, in order.
        table: Vec<chisel_bsp::tree::Label>,
    },
    /// A quadric prop whose solid cannot be told convex, so no convex tool
    /// can follow it ([`super::CarveTool::from_prop`]).
    #[error(
        "the prop cannot be carved with: {reason}; a prop tool must be one intersection \
         of convex quadric solids (ellipsoids, elliptic cylinders and paraboloids) and \
         half-spaces; carve with its convex parts one by one instead"
    )]
    PropNotConvex {
        /// Which part of the prop is not convex, and why.
        reason: String,
    },
    /// A quadric prop that gives no tool for another reason: its scene
    /// does not normalize, its solid is empty or unbounded, or no point
    /// inside it was found.
    #[error("the prop cannot be carved with: {reason}")]
    InvalidProp {
        /// What is wrong with it.
        reason: String,
    },
    /// Undo was asked for, but no carve is left to undo.
    #[error("there is no carve left to undo")]
    NothingToUndo,
    /// Redo was asked for ([`super::RedoCarve`]), but no undone carve is
    /// left to redo: none was undone, or a carve, a load or a detach
    /// across chunk borders came after the undo.
    #[error("there is no undone carve left to redo")]
    NothingToRedo,
    /// The entity named in a message has no [`super::Terrain`].
    #[error("the entity has no Terrain component; carve a terrain entity")]
    NoSuchTerrain,
    /// A heightfield that cannot be used.
    #[error("invalid heightfield: {reason}")]
    InvalidHeightfield {
        /// What is wrong with it.
        reason: String,
    },
    /// A Bevy mesh that cannot be imported (wrong topology, no positions).
    #[error("cannot import the mesh: {reason}; give a closed triangle list with positions")]
    InvalidMesh {
        /// What is wrong with it.
        reason: &'static str,
    },
    /// Reading or writing a file failed.
    #[error("terrain file: {message}")]
    Io {
        /// The operating system's message.
        message: String,
    },
    /// The file does not start with the terrain file magic: it is not a
    /// terrain file.
    #[error("not a bevy_chisel terrain file (bad magic)")]
    BadMagic,
    /// The file was written by a format version this build cannot read.
    #[error(
        "terrain file version {found} is not supported (this build reads version \
         {supported}); re-save it with a matching build"
    )]
    UnsupportedVersion {
        /// Version found in the file.
        found: u32,
        /// The version this build reads and writes.
        supported: u32,
    },
    /// The file ends in the middle of a record.
    #[error("terrain file is truncated: data missing at byte {at}")]
    Truncated {
        /// Byte offset where more data was expected.
        at: usize,
    },
    /// The file's content is inconsistent (bad checksum, unknown tags,
    /// values out of range, or an octree snapshot the kernel's checks
    /// refuse).
    #[error("terrain file is corrupt: {reason}")]
    Corrupt {
        /// What was found.
        reason: String,
    },
    /// A terrain world's layout, streaming settings or source is unusable,
    /// or a chunk file belongs to another world.
    #[error("invalid terrain world: {reason}")]
    InvalidWorld {
        /// What is wrong.
        reason: String,
    },
    /// A [`super::WorldCarve`] names a networked world (feature `net`):
    /// its server orders every carve, so one applied here alone would
    /// leave this peer out of step. Send a `NetWorldCarveRequest` instead:
    /// the server orders it as any other (a listen-server host's own
    /// included; the `net` module's "Roles").
    #[error("a networked terrain world is carved through its server (NetWorldCarveRequest)")]
    NetworkedWorld,
    /// A terrain world holds no whole state: a carve or undo waits for a
    /// chunk or a live chunk has a carve, undo or detach queued or
    /// running. [`super::TerrainWorld::save`] refuses such a world at
    /// once; a [`super::SaveWorld`] waits for a whole state, or after
    /// [`super::TerrainWorld::save_settle_frames`] a consistent one (no
    /// world carve landed in some of its chunks and not in others), and
    /// reports this only when neither came in
    /// [`super::TerrainWorld::max_save_wait`] frames of its turn.
    #[error("terrain world chunk {chunk:?} has carves in progress; save when the world is settled")]
    WorldNotIdle {
        /// A busy chunk (x, z).
        chunk: [i64; 2],
    },
    /// [`super::TerrainWorld::save`] was called while a save of this
    /// terrain world ([`super::SaveWorld`]) is being written; call it
    /// again once its [`super::WorldSaved`] or [`super::WorldSaveFailed`]
    /// is read. A [`super::SaveWorld`] is never refused for this: it
    /// waits for the save being written.
    #[error(
        "terrain world save to {folder} is still being written; save again once it is reported"
    )]
    WorldSaveRunning {
        /// The folder of the save being written.
        folder: String,
    },
    /// A point query of a terrain world
    /// ([`super::TerrainWorld::material_at`]) fell in a chunk that is not
    /// live (streamed out, being built or never built), whose material is
    /// not in memory. Ask near a [`super::TerrainFocus`], or read the
    /// chunk's [`super::Terrain`] once it streams in.
    #[error(
        "terrain world chunk {chunk:?} is not loaded; ask for points in chunks a focus keeps live"
    )]
    ChunkNotLoaded {
        /// The chunk (x, z).
        chunk: [i64; 2],
    },
    /// A file could not be read as a terrain ([`super::Terrain::load`]) or
    /// a world's chunk ([`super::TerrainWorld::load_edits`]): `path` names
    /// it, `error` is why ([`TerrainError::BadMagic`],
    /// [`TerrainError::UnsupportedVersion`], [`TerrainError::Truncated`],
    /// [`TerrainError::Corrupt`] or another error of the terrain it holds;
    /// also [`TerrainError::in_file`]).
    #[error("{path}: {error}")]
    InFile {
        /// The file.
        path: String,
        /// What is wrong with it.
        error: Box<TerrainError>,
    },
}

impl TerrainError {
    /// What is wrong, without the file it was found in: the `error` of a
    /// [`TerrainError::InFile`], else this error.
    #[must_use]
    pub fn in_file(&self) -> &TerrainError {
        match self {
            TerrainError::InFile { error, .. } => error.in_file(),
            other => other,
        }
    }

    /// This error, found in the file at `path`.
    pub(crate) fn at_path(self, path: &std::path::Path) -> TerrainError {
        TerrainError::InFile {
            path: path.display().to_string(),
            error: Box::new(self),
        }
    }
}

impl From<chisel_bsp::Error> for TerrainError {
    fn from(e: chisel_bsp::Error) -> Self {
        TerrainError::Kernel(e)
    }
}

impl From<std::io::Error> for TerrainError {
    fn from(e: std::io::Error) -> Self {
        TerrainError::Io {
            message: e.to_string(),
        }
    }
}
