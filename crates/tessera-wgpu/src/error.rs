//! The one error type of `tessera-wgpu`.

/// What can go wrong in the GPU stage.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// No GPU adapter (not even a CPU one such as lavapipe) could be found.
    #[error("no GPU adapter ({0}); install a Vulkan driver: on Debian or Ubuntu, `apt-get install mesa-vulkan-drivers` gives Mesa's lavapipe, which runs on the CPU (`cargo xtask render` installs it)")]
    NoAdapter(String),
    /// The adapter refused the device (limits or features).
    #[error("requesting a device failed: {0}")]
    RequestDevice(String),
    /// A stage was given [`crate::Kernels`] made for another device.
    #[error("the kernels were made for another device; make a Kernels for this one")]
    ForeignKernels,
    /// wgpu reported a validation or out-of-memory error.
    #[error("wgpu error: {0}")]
    Wgpu(String),
    /// A run needs an output buffer larger than the device allows.
    #[error("the {what} buffer would need {bytes} bytes, over the device's limit of {limit}; a coarser tolerance or threshold, or a smaller depth, needs less")]
    OutputTooLarge {
        /// Which buffer.
        what: &'static str,
        /// Bytes it would need.
        bytes: u64,
        /// The device's limit.
        limit: u64,
    },
    /// The surface's upload (patch data) needs a buffer larger than the device allows.
    #[error("the model's {what} need {bytes} bytes on the GPU, over the device's limit of {limit} per buffer; tessellate it with --backend cpu or split the mesh")]
    ModelTooLarge {
        /// Which part of the model.
        what: &'static str,
        /// Bytes it would need.
        bytes: u64,
        /// The device's limit.
        limit: u64,
    },
    /// The displacement-map atlas of a Bézier model needs a texture larger than the
    /// device allows (256 patches per row of 16×16 texels).
    #[error("the model's {patches} patches need a {width}×{height} displacement-map atlas, over the device's texture limit of {limit}; tessellate it with --backend cpu or split the model")]
    MapAtlasTooLarge {
        /// Patches of the model.
        patches: u32,
        /// Texels across the atlas.
        width: u32,
        /// Texels down the atlas.
        height: u32,
        /// The device's largest texture side.
        limit: u32,
    },
    /// A Catmull-Clark model derives more Bézier nets than the stage's four pages hold
    /// ([`tessera_core::gpu_types::CcNetLayout`]: textures as large as the device allows,
    /// up to 16384 texels a side).
    #[error("the model's quadtrees need {nets} Bézier nets, over the {capacity} that the stage's four net textures hold on this device; tessellate it with --backend cpu or split the mesh")]
    TooManyNets {
        /// Nets the model derives.
        nets: u64,
        /// Nets the device's textures hold.
        capacity: u64,
    },
    /// The device could not allocate what a stage needs (its memory, or the most one
    /// allocation may take).
    #[error("the device could not allocate {what} ({detail}); tessellate it with --backend cpu or split the mesh")]
    OutOfMemory {
        /// What was being allocated.
        what: &'static str,
        /// The device's answer.
        detail: String,
    },
    /// Waiting for the GPU or mapping a buffer failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
    /// The input or a parameter was rejected by the core.
    #[error(transparent)]
    Core(#[from] tessera_core::Error),
    /// Writing an image failed.
    #[error("{path}: {msg}")]
    Image {
        /// The file.
        path: String,
        /// What went wrong.
        msg: String,
    },
    /// A render was asked for something the device or the renderer cannot do (an image
    /// size beyond the device's limits, say).
    #[error("rendering: {0}")]
    Render(String),
    /// A snapshot did not match its reference, or the reference is missing.
    #[error("snapshot {name}: {msg}")]
    Snapshot {
        /// The snapshot's name.
        name: String,
        /// What differed.
        msg: String,
    },
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
