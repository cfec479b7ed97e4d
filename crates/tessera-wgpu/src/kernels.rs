//! The compiled kernels of one device, shared by every stage made on it.

use std::sync::{Arc, OnceLock};

use crate::bezier::BezierKernels;
use crate::catmull_clark::{CcKernels, CcStencilKernels, CcUniformKernels, NetPages};

/// The compute pipelines of one device. Compiling them is the slow part of creating a
/// stage (seconds on a CPU driver), so they are compiled once, each family the first
/// time a stage needs it, and shared by every stage given this set. Cloning is cheap.
///
/// ```no_run
/// # fn f(device: &wgpu::Device) {
/// let kernels = tessera_wgpu::Kernels::new(device);
/// // BezierStage::new(device, queue, &kernels, …), CcStage::new(device, queue, &kernels, …)
/// # }
/// ```
#[derive(Clone)]
pub struct Kernels(Arc<Inner>);

struct Inner {
    device: wgpu::Device,
    bezier: OnceLock<BezierKernels>,
    /// The Catmull-Clark families, each for one net page and for four ([`NetPages`]).
    cc: [OnceLock<Arc<CcKernels>>; 2],
    cc_uniform: [OnceLock<Arc<CcUniformKernels>>; 2],
    cc_stencil: [OnceLock<Arc<CcStencilKernels>>; 2],
}

impl Kernels {
    /// An empty set for `device`: nothing is compiled until a stage needs it.
    pub fn new(device: &wgpu::Device) -> Self {
        Kernels(Arc::new(Inner {
            device: device.clone(),
            bezier: OnceLock::new(),
            cc: Default::default(),
            cc_uniform: Default::default(),
            cc_stencil: Default::default(),
        }))
    }

    /// Fails unless these kernels were made for `device`: pipelines of one device cannot
    /// run on another. wgpu tells devices apart within one `Instance` (their ids), which
    /// is where a renderer makes its devices.
    pub(crate) fn check_device(&self, device: &wgpu::Device) -> crate::Result<()> {
        if &self.0.device == device {
            Ok(())
        } else {
            Err(crate::Error::ForeignKernels)
        }
    }

    pub(crate) fn bezier(&self) -> &BezierKernels {
        self.0
            .bezier
            .get_or_init(|| BezierKernels::new(&self.0.device))
    }

    pub(crate) fn cc(&self, pages: NetPages) -> Arc<CcKernels> {
        self.0.cc[pages.index()]
            .get_or_init(|| {
                Arc::new(CcKernels::new(
                    &self.0.device,
                    self.cc_stencil(pages),
                    pages,
                ))
            })
            .clone()
    }

    /// The stencil step both Catmull-Clark stages run first.
    pub(crate) fn cc_stencil(&self, pages: NetPages) -> Arc<CcStencilKernels> {
        self.0.cc_stencil[pages.index()]
            .get_or_init(|| Arc::new(CcStencilKernels::new(&self.0.device, pages)))
            .clone()
    }

    pub(crate) fn cc_uniform(&self, pages: NetPages) -> Arc<CcUniformKernels> {
        self.0.cc_uniform[pages.index()]
            .get_or_init(|| Arc::new(CcUniformKernels::new(&self.0.device, pages)))
            .clone()
    }
}
