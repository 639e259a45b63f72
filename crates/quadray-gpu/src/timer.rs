//! Timestamp-query timing: a technique brackets each pass it wants timed with
//! [`GpuTimer::compute_pass`] / [`GpuTimer::render_pass`] writes, renders N frames, and reads the
//! medians back. CPU wall time never stands in for GPU time.

use crate::{Gpu, GpuError};
use std::ops::Range;
use std::sync::atomic::{AtomicU8, AtomicU64, Ordering};

pub use quadray_core::stats::Summary as TimingSummary;

/// Bytes between two passes' timestamps in the resolve buffer (`QUERY_RESOLVE_BUFFER_ALIGNMENT`).
const RESOLVE_STRIDE: u64 = wgpu::QUERY_RESOLVE_BUFFER_ALIGNMENT;

/// What [`GpuTimer::resolve`] records into: a command encoder, or a recorder of the queries it
/// resolves. Resolving a query no pass wrote passes wgpu's validation, yet never finishes on
/// NVIDIA's driver, so only a recording shows which queries a resolve would wait for.
pub trait ResolveEncoder {
    /// [`wgpu::CommandEncoder::resolve_query_set`].
    fn resolve_query_set(
        &mut self,
        query_set: &wgpu::QuerySet,
        queries: Range<u32>,
        destination: &wgpu::Buffer,
        destination_offset: u64,
    );
    /// [`wgpu::CommandEncoder::copy_buffer_to_buffer`].
    fn copy_buffer_to_buffer(
        &mut self,
        source: &wgpu::Buffer,
        source_offset: u64,
        destination: &wgpu::Buffer,
        destination_offset: u64,
        size: u64,
    );
}

impl ResolveEncoder for wgpu::CommandEncoder {
    fn resolve_query_set(
        &mut self,
        query_set: &wgpu::QuerySet,
        queries: Range<u32>,
        destination: &wgpu::Buffer,
        destination_offset: u64,
    ) {
        wgpu::CommandEncoder::resolve_query_set(
            self,
            query_set,
            queries,
            destination,
            destination_offset,
        );
    }

    fn copy_buffer_to_buffer(
        &mut self,
        source: &wgpu::Buffer,
        source_offset: u64,
        destination: &wgpu::Buffer,
        destination_offset: u64,
        size: u64,
    ) {
        wgpu::CommandEncoder::copy_buffer_to_buffer(
            self,
            source,
            source_offset,
            destination,
            destination_offset,
            size,
        );
    }
}

/// A query set with room for `passes` begin/end pairs, resolved once per frame.
pub struct GpuTimer {
    query_set: Option<wgpu::QuerySet>,
    resolve: Option<wgpu::Buffer>,
    readback: Option<wgpu::Buffer>,
    passes: u32,
    /// One bit a pass: the passes given timestamp writes since the last resolve. Only these are
    /// resolved: resolving a query no pass wrote waits for it forever on some drivers (wgpu's
    /// Vulkan backend copies query results with `VK_QUERY_RESULT_WAIT_BIT`; NVIDIA's driver
    /// then never finishes the submission, lavapipe returns at once).
    written: AtomicU64,
    /// The passes the last resolve copied, which [`Self::collect`] reads.
    resolved: AtomicU64,
    /// While [`Self::span`] records part of a span: bit 0 leaves out the passes' beginnings,
    /// bit 1 their ends.
    span: AtomicU8,
    period_ns: f64,
    /// Per pass, the durations of every frame recorded so far (ms).
    samples: Vec<Vec<f64>>,
}

impl GpuTimer {
    /// A timer for `passes` passes (at most 64).
    pub fn new(gpu: &Gpu, passes: u32) -> Self {
        assert!(
            passes <= 64,
            "a GpuTimer times at most 64 passes, not {passes}"
        );
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
                    size: u64::from(passes) * RESOLVE_STRIDE,
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
            written: AtomicU64::new(0),
            resolved: AtomicU64::new(0),
            span: AtomicU8::new(0),
            period_ns: f64::from(gpu.queue.get_timestamp_period()),
            samples: vec![Vec::new(); passes as usize],
        }
    }

    pub fn enabled(&self) -> bool {
        self.query_set.is_some()
    }

    /// The timestamp writes of pass `pass`; the pass must be recorded with them (its queries are
    /// resolved at the next [`Self::resolve`]). Inside [`Self::span`], only the span's ends.
    pub fn render_pass(&self, pass: u32) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (query_set, beginning, end) = self.writes(pass)?;
        Some(wgpu::RenderPassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: beginning,
            end_of_pass_write_index: end,
        })
    }

    /// The timestamp writes of pass `pass`, as [`Self::render_pass`].
    pub fn compute_pass(&self, pass: u32) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (query_set, beginning, end) = self.writes(pass)?;
        Some(wgpu::ComputePassTimestampWrites {
            query_set,
            beginning_of_pass_write_index: beginning,
            end_of_pass_write_index: end,
        })
    }

    /// Records `record`'s timed passes as part of a span that several recordings time together
    /// in one slot (the same pass once per light view): their beginnings only when `first`,
    /// their ends only when `last`, so a slot times from its first recording's start to its last
    /// one's end.
    pub fn span<R>(&self, first: bool, last: bool, record: impl FnOnce() -> R) -> R {
        let part = u8::from(!first) | (u8::from(!last) << 1);
        self.span.store(part, Ordering::Relaxed);
        let out = record();
        self.span.store(0, Ordering::Relaxed);
        out
    }

    /// Pass `pass`'s query set and its beginning's and end's query indices as the span allows
    /// (`None` for a recording in the middle of a span, or without timestamp queries); the pass
    /// is resolved once its end is written.
    #[allow(clippy::type_complexity)]
    fn writes(&self, pass: u32) -> Option<(&wgpu::QuerySet, Option<u32>, Option<u32>)> {
        let part = self.span.load(Ordering::Relaxed);
        let (beginning, end) = (part & 1 == 0, part & 2 == 0);
        if end {
            self.mark(pass);
        }
        let query_set = self.query_set.as_ref()?;
        (beginning || end).then_some((
            query_set,
            beginning.then_some(pass * 2),
            end.then_some(pass * 2 + 1),
        ))
    }

    fn mark(&self, pass: u32) {
        assert!(
            pass < self.passes,
            "pass {pass} of a timer for {}",
            self.passes
        );
        self.written.fetch_or(1 << pass, Ordering::Relaxed);
    }

    /// Records the resolve of this frame's timestamps, those of the passes given writes since the
    /// last resolve; call after the timed passes, before finish.
    pub fn resolve(&self, encoder: &mut impl ResolveEncoder) {
        let written = self.written.swap(0, Ordering::Relaxed);
        self.resolved.store(written, Ordering::Relaxed);
        if let (Some(q), Some(resolve), Some(readback)) =
            (&self.query_set, &self.resolve, &self.readback)
        {
            for pass in self.passes_in(written) {
                // a resolve's destination offset must be 256-aligned: one slot a pass
                let slot = u64::from(pass) * RESOLVE_STRIDE;
                encoder.resolve_query_set(q, pass * 2..pass * 2 + 2, resolve, slot);
                encoder.copy_buffer_to_buffer(resolve, slot, readback, u64::from(pass) * 16, 16);
            }
        }
    }

    /// The passes the next [`Self::resolve`] resolves: those given timestamp writes since the
    /// last one.
    pub fn passes_to_resolve(&self) -> Vec<u32> {
        self.passes_in(self.written.load(Ordering::Relaxed))
    }

    fn passes_in(&self, mask: u64) -> Vec<u32> {
        (0..self.passes).filter(|p| mask & (1 << p) != 0).collect()
    }

    /// Reads this frame's timestamps (after the encoder with [`Self::resolve`] was submitted) and
    /// adds one sample per pass. Passes that were not recorded this frame are skipped.
    pub fn collect(&mut self, gpu: &Gpu) -> Result<(), GpuError> {
        let Some(readback) = &self.readback else {
            return Ok(());
        };
        let resolved = self.resolved.load(Ordering::Relaxed);
        let ticks: Vec<u64> =
            crate::readback::map_buffer(gpu, readback, "the pass timestamps", |bytes| {
                bytemuck::cast_slice(bytes).to_vec()
            })?;
        for (pass, pair) in ticks.chunks_exact(2).enumerate() {
            if resolved & (1 << pass) != 0 && pair[1] > pair[0] {
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
