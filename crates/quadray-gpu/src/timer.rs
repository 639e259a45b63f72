//! Timestamp-query timing: a technique brackets each pass it wants timed with
//! [`GpuTimer::compute_pass`] / [`GpuTimer::render_pass`] writes, renders N frames, and reads the
//! medians back. CPU wall time never stands in for GPU time.

use crate::{Gpu, GpuError};

pub use quadray_core::stats::Summary as TimingSummary;

/// A query set with room for `passes` begin/end pairs, resolved once per frame.
pub struct GpuTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    passes: u32,
    period_ns: f64,
    /// Per pass, the durations of every frame recorded so far (ms).
    samples: Vec<Vec<f64>>,
}

impl GpuTimer {
    pub fn new(gpu: &Gpu, passes: u32) -> Self {
        let count = passes * 2;
        let (query_set, resolve, readback) = if gpu.has_timestamps {
            let size = u64::from(count) * 8;
            (
                Some(gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                    label: Some("pass timestamps"),
                    ty: wgpu::QueryType::Timestamp,
                    count,
                })),
                Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp resolve"),
                    size,
                    usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                    mapped_at_creation: false,
                })),
                Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("timestamp readback"),
                    size,
                    usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })),
            )
        } else {
            (None, None, None)
        };
        Self {
            query_set,
            resolve,
            readback,
            passes,
            period_ns: f64::from(gpu.queue.get_timestamp_period()),
            samples: vec![Vec::new(); passes as usize],
        }
    }

    pub fn enabled(&self) -> bool {
        self.query_set.is_some()
    }

    pub fn render_pass(&self, pass: u32) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        self.query_set
            .as_ref()
            .map(|query_set| wgpu::RenderPassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(pass * 2),
                end_of_pass_write_index: Some(pass * 2 + 1),
            })
    }

    pub fn compute_pass(&self, pass: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        self.query_set
            .as_ref()
            .map(|query_set| wgpu::ComputePassTimestampWrites {
                query_set,
                beginning_of_pass_write_index: Some(pass * 2),
                end_of_pass_write_index: Some(pass * 2 + 1),
            })
    }

    /// Records the resolve of this frame's timestamps; call after the timed passes, before finish.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if let (Some(q), Some(resolve), Some(readback)) =
            (&self.query_set, &self.resolve, &self.readback)
        {
            encoder.resolve_query_set(q, 0..self.passes * 2, resolve, 0);
            encoder.copy_buffer_to_buffer(resolve, 0, readback, 0, resolve.size());
        }
    }

    /// Reads this frame's timestamps (after the encoder with [`Self::resolve`] was submitted) and
    /// adds one sample per pass. Passes that were not recorded this frame are skipped.
    pub fn collect(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let Some(readback) = &self.readback else {
            return Ok(());
        };
        let ticks: Vec<u64> = crate::readback::map_buffer(gpu, readback, |bytes| {
            bytemuck::cast_slice(bytes).to_vec()
        })?;
        for (pass, pair) in ticks.chunks_exact(2).enumerate() {
            if pair[1] > pair[0] {
                let ms = (pair[1] - pair[0]) as f64 * self.period_ns * 1e-6;
                self.samples[pass].push(ms);
            }
        }
        Ok(())
    }

    /// Medians of every pass so far; `None` for passes never timed (or without timestamp support).
    pub fn summaries(&self) -> Vec<Option<TimingSummary>> {
        self.samples
            .iter()
            .map(|s| TimingSummary::from_samples(&mut s.clone()))
            .collect()
    }

    pub fn clear(&mut self) {
        self.samples.iter_mut().for_each(Vec::clear);
    }
}
