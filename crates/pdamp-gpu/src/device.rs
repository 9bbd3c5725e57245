//! Opening a GPU (or lavapipe) through wgpu/Vulkan with 64-bit float shaders.

use crate::GpuError;

/// An opened device with its queue.
pub struct GpuDevice {
    pub(crate) device: wgpu::Device,
    pub(crate) queue: wgpu::Queue,
    info: wgpu::AdapterInfo,
    limits: wgpu::Limits,
}

impl std::fmt::Debug for GpuDevice {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("GpuDevice")
            .field("adapter", &self.info.name)
            .finish()
    }
}

impl GpuDevice {
    /// Opens the best Vulkan adapter with `SHADER_F64`: a discrete or integrated GPU first,
    /// else a CPU driver (lavapipe). `PDAMP_GPU_ADAPTER=cpu` forces the CPU driver,
    /// `PDAMP_GPU_ADAPTER=gpu` refuses it.
    pub fn open() -> Result<Self, GpuError> {
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::VULKAN;
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let want = std::env::var("PDAMP_GPU_ADAPTER").unwrap_or_default();
        let mut seen = Vec::new();
        let mut best: Option<(u32, wgpu::Adapter)> = None;
        for a in adapters {
            let info = a.get_info();
            let f64_ok = a.features().contains(wgpu::Features::SHADER_F64);
            seen.push(format!(
                "{} ({:?}, f64 {})",
                info.name, info.device_type, f64_ok
            ));
            if !f64_ok {
                continue;
            }
            let cpu = info.device_type == wgpu::DeviceType::Cpu;
            if (want == "cpu" && !cpu) || (want == "gpu" && cpu) {
                continue;
            }
            let rank = match info.device_type {
                wgpu::DeviceType::DiscreteGpu => 3,
                wgpu::DeviceType::IntegratedGpu => 2,
                wgpu::DeviceType::Cpu => 1,
                _ => 0,
            };
            if best.as_ref().is_none_or(|(r, _)| rank > *r) {
                best = Some((rank, a));
            }
        }
        let Some((_, adapter)) = best else {
            return Err(GpuError::NoAdapter(if seen.is_empty() {
                "no Vulkan adapter at all".into()
            } else {
                format!("adapters: {}", seen.join(", "))
            }));
        };
        let info = adapter.get_info();
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < 27 {
            return Err(GpuError::Device(format!(
                "{} allows {} storage buffers per shader stage, the kernels use 27",
                info.name, limits.max_storage_buffers_per_shader_stage
            )));
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("pdamp-gpu"),
            required_features: wgpu::Features::SHADER_F64,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device(format!("{}: {e}", info.name)))?;
        Ok(Self {
            device,
            queue,
            info,
            limits,
        })
    }

    /// Name and driver of the adapter, e.g. "NVIDIA H200 (NVIDIA 580.159.04)".
    pub fn name(&self) -> String {
        format!(
            "{} ({} {})",
            self.info.name, self.info.driver, self.info.driver_info
        )
    }

    /// Whether this is a CPU driver (lavapipe) rather than a GPU.
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    pub(crate) fn limits(&self) -> &wgpu::Limits {
        &self.limits
    }
}
