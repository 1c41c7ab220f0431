// cellsuite: this file is rewritten from its start to the `mod tests` line (vendor/README.md,
// patch 4): reassembly grows only as fragments arrive, within caps. The 0.15.1 release
// allocated and zeroed each sample's announced size (up to 4 GiB) on its first fragment.
use std::{
  collections::BTreeMap,
  fmt, iter,
  sync::{
    atomic::{AtomicU64, AtomicUsize, Ordering},
    Mutex,
  },
  time::{Duration, Instant},
};

use enumflags2::BitFlags;
use bytes::{Bytes, BytesMut};
#[allow(unused_imports)]
use log::{debug, error, info, trace, warn};

use crate::{
  dds::ddsdata::DDSData,
  messages::submessages::{
    elements::serialized_payload::SerializedPayload,
    submessages::{DATAFRAG_Flags, DataFrag},
  },
  structure::{
    cache_change::ChangeKind,
    sequence_number::{FragmentNumber, SequenceNumber},
    time::Timestamp,
  },
};

/// Caps on the reassembly of fragmented samples (DATA_FRAG, RTPS 2.5 §8.3.7.3 and
/// §8.4.14.1), for the whole process: see [`set_fragment_reassembly_limits`].
///
/// A DATA_FRAG announces its sample's size (`sampleSize`, up to 4 GiB) before any data
/// arrives. Memory is taken only for fragments that did arrive, and a fragment that would
/// break a cap is dropped (one rate-limited log line), so no message can exhaust memory.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FragmentReassemblyLimits {
  /// The largest sample (serialized bytes) reassembled; a larger one is dropped whole.
  pub max_sample_size: usize,
  /// Samples of one remote writer reassembled at once. Reliable readers keep the oldest
  /// (they deliver in order, and the writer resends the rest); best-effort ones the newest.
  pub max_open_samples_per_writer: usize,
  /// Bytes held by all incomplete samples of the process together, all readers included.
  pub max_buffered_bytes: usize,
}

impl FragmentReassemblyLimits {
  /// 64 MiB: sixteen times the largest sample the cellsuite sends (a 1024 × 1024 f32
  /// heat map, 4 MiB).
  pub const DEFAULT_MAX_SAMPLE_SIZE: usize = 64 << 20;
  /// Fragments of one sample arrive back to back, so a few are open at once.
  pub const DEFAULT_MAX_OPEN_SAMPLES_PER_WRITER: usize = 32;
  /// Four samples of the largest size.
  pub const DEFAULT_MAX_BUFFERED_BYTES: usize = 256 << 20;
}

impl Default for FragmentReassemblyLimits {
  fn default() -> Self {
    Self {
      max_sample_size: Self::DEFAULT_MAX_SAMPLE_SIZE,
      max_open_samples_per_writer: Self::DEFAULT_MAX_OPEN_SAMPLES_PER_WRITER,
      max_buffered_bytes: Self::DEFAULT_MAX_BUFFERED_BYTES,
    }
  }
}

static MAX_SAMPLE_SIZE: AtomicUsize =
  AtomicUsize::new(FragmentReassemblyLimits::DEFAULT_MAX_SAMPLE_SIZE);
static MAX_OPEN_SAMPLES_PER_WRITER: AtomicUsize =
  AtomicUsize::new(FragmentReassemblyLimits::DEFAULT_MAX_OPEN_SAMPLES_PER_WRITER);
static MAX_BUFFERED_BYTES: AtomicUsize =
  AtomicUsize::new(FragmentReassemblyLimits::DEFAULT_MAX_BUFFERED_BYTES);

/// Sets the caps on fragment reassembly for every reader of the process, from the next
/// fragment on. Limits of zero are raised to one.
pub fn set_fragment_reassembly_limits(limits: FragmentReassemblyLimits) {
  MAX_SAMPLE_SIZE.store(limits.max_sample_size.max(1), Ordering::Relaxed);
  MAX_OPEN_SAMPLES_PER_WRITER.store(limits.max_open_samples_per_writer.max(1), Ordering::Relaxed);
  MAX_BUFFERED_BYTES.store(limits.max_buffered_bytes.max(1), Ordering::Relaxed);
}

/// The caps in force.
pub fn fragment_reassembly_limits() -> FragmentReassemblyLimits {
  FragmentReassemblyLimits {
    max_sample_size: MAX_SAMPLE_SIZE.load(Ordering::Relaxed),
    max_open_samples_per_writer: MAX_OPEN_SAMPLES_PER_WRITER.load(Ordering::Relaxed),
    max_buffered_bytes: MAX_BUFFERED_BYTES.load(Ordering::Relaxed),
  }
}

/// Bytes charged to all incomplete samples of the process (payload and bookkeeping).
static BUFFERED_BYTES: AtomicUsize = AtomicUsize::new(0);
/// Bookkeeping charged per stored run of fragments and per open sample, so that tiny
/// fragments cannot hold much more memory than the budget says.
const RUN_OVERHEAD: usize = 64;
const SAMPLE_OVERHEAD: usize = 256;
/// A NACK_FRAG names at most 256 fragments (FragmentNumberSet, RTPS 2.5 §9.4.2.8).
const MAX_FRAGMENTS_NACKED: usize = 256;

fn reserve_buffered(bytes: usize, budget: usize) -> bool {
  BUFFERED_BYTES
    .fetch_update(Ordering::Relaxed, Ordering::Relaxed, |held| {
      held.checked_add(bytes).filter(|total| *total <= budget)
    })
    .is_ok()
}

fn release_buffered(bytes: usize) {
  BUFFERED_BYTES.fetch_sub(bytes, Ordering::Relaxed);
}

/// Logs a dropped DATA_FRAG (an error: a peer sent something no correct writer sends, or more
/// than the caps allow): at most one line per 5 s, counting the ones not logged.
fn log_dropped(sn: SequenceNumber, why: fmt::Arguments<'_>) {
  static LAST_LINE: Mutex<Option<Instant>> = Mutex::new(None);
  static UNLOGGED: AtomicU64 = AtomicU64::new(0);
  let Ok(mut last) = LAST_LINE.lock() else {
    return;
  };
  let now = Instant::now();
  if last.is_some_and(|t| now.duration_since(t) < Duration::from_secs(5)) {
    UNLOGGED.fetch_add(1, Ordering::Relaxed);
    return;
  }
  *last = Some(now);
  let unlogged = UNLOGGED.swap(0, Ordering::Relaxed);
  error!(
    "DATA_FRAG of sample {sn:?} dropped: {why} ({unlogged} more dropped since the last such line)"
  );
}

/// What a DATA_FRAG says about its part of a sample, checked against itself.
struct FragRun {
  data_size: u32,
  fragment_size: u16,
  fragment_count: u32,
  /// Fragments `first .. end`, counted from 0.
  first: u32,
  end: u32,
}

impl FragRun {
  /// The run a DATA_FRAG carries, or why it is malformed or too large.
  fn of(datafrag: &DataFrag, max_sample_size: usize) -> Result<Self, String> {
    let data_size = datafrag.data_size;
    let fragment_size = datafrag.fragment_size;
    if fragment_size == 0 || data_size == 0 || u32::from(fragment_size) > data_size {
      return Err(format!(
        "malformed: fragment size {fragment_size}, sample size {data_size}"
      ));
    }
    if usize::try_from(data_size).map_or(true, |size| size > max_sample_size) {
      return Err(format!(
        "sample size {data_size} is over the limit of {max_sample_size} bytes"
      ));
    }
    let fragment_count = data_size.div_ceil(u32::from(fragment_size));
    let starting = u32::from(datafrag.fragment_starting_num);
    let in_submessage = u32::from(datafrag.fragments_in_submessage);
    let end = u64::from(starting) + u64::from(in_submessage) - 1;
    if starting == 0 || in_submessage == 0 || end > u64::from(fragment_count) {
      return Err(format!(
        "malformed: fragments {starting} + {in_submessage} of {fragment_count}"
      ));
    }
    let run = Self {
      data_size,
      fragment_size,
      fragment_count,
      first: starting - 1,
      end: end as u32, // <= fragment_count, a u32
    };
    if datafrag.serialized_payload.len() < run.byte_range(run.first, run.end).len() {
      return Err(format!(
        "malformed: {} payload bytes for fragments {starting} + {in_submessage} of {fragment_size} bytes",
        datafrag.serialized_payload.len()
      ));
    }
    Ok(run)
  }

  /// Bytes of fragments `first .. end` within the sample (the last fragment may be short).
  fn byte_range(&self, first: u32, end: u32) -> std::ops::Range<usize> {
    let size = u64::from(self.fragment_size);
    let at = |f: u32| (u64::from(f) * size).min(u64::from(self.data_size)) as usize;
    at(first)..at(end)
  }
}

// One sample being reassembled: the runs of fragments received so far.
struct AssemblyBuffer {
  data_size: u32,
  fragment_size: u16,
  fragment_count: u32,
  /// Non-overlapping runs by first fragment (from 0): the run's end and its bytes.
  runs: BTreeMap<u32, (u32, Bytes)>,
  received_fragments: u32,
  /// Bytes charged to BUFFERED_BYTES, given back on drop.
  charged: usize,
  modified_time: Timestamp,
}

impl Drop for AssemblyBuffer {
  fn drop(&mut self) {
    release_buffered(self.charged);
  }
}

impl AssemblyBuffer {
  /// An empty buffer for the sample of `run`, charged its bookkeeping, or `None` when the
  /// budget has no room.
  fn new(run: &FragRun, budget: usize) -> Option<Self> {
    reserve_buffered(SAMPLE_OVERHEAD, budget).then(|| Self {
      data_size: run.data_size,
      fragment_size: run.fragment_size,
      fragment_count: run.fragment_count,
      runs: BTreeMap::new(),
      received_fragments: 0,
      charged: SAMPLE_OVERHEAD,
      modified_time: Timestamp::now(),
    })
  }

  fn same_sample(&self, run: &FragRun) -> bool {
    self.data_size == run.data_size && self.fragment_size == run.fragment_size
  }

  /// The parts of fragments `first .. end` not received yet.
  fn gaps(&self, first: u32, end: u32) -> Vec<(u32, u32)> {
    let mut gaps = Vec::new();
    let mut at = first;
    let before = self.runs.range(..first).next_back();
    for (&run_first, &(run_end, _)) in before.into_iter().chain(self.runs.range(first..end)) {
      if run_first > at {
        gaps.push((at, run_first.min(end)));
      }
      at = at.max(run_end);
      if at >= end {
        break;
      }
    }
    if at < end {
      gaps.push((at, end));
    }
    gaps
  }

  /// Stores the fragments of `run` not received yet, copied out of `payload`. `false` if
  /// the budget has no room for them (nothing is stored then).
  fn insert(&mut self, run: &FragRun, payload: &[u8], budget: usize) -> bool {
    let gaps = self.gaps(run.first, run.end);
    let start = run.byte_range(0, run.first).end;
    let charge: usize = gaps
      .iter()
      .map(|&(f, e)| run.byte_range(f, e).len() + RUN_OVERHEAD)
      .sum();
    if !reserve_buffered(charge, budget) {
      return false;
    }
    self.charged += charge;
    for (f, e) in gaps {
      let bytes = run.byte_range(f, e);
      let bytes = Bytes::copy_from_slice(&payload[bytes.start - start..bytes.end - start]);
      self.runs.insert(f, (e, bytes));
      self.received_fragments += e - f;
    }
    self.modified_time = Timestamp::now();
    true
  }

  fn is_complete(&self) -> bool {
    self.received_fragments == self.fragment_count
  }

  /// The whole sample; only when complete.
  fn assembled(&self) -> Bytes {
    let mut sample = BytesMut::with_capacity(self.data_size as usize);
    for (_, bytes) in self.runs.values() {
      sample.extend_from_slice(bytes);
    }
    sample.freeze()
  }

  /// Missing fragments, from 0, at most as many as a NACK_FRAG names.
  fn missing(&self) -> impl '_ + Iterator<Item = u32> {
    self
      .gaps(0, self.fragment_count)
      .into_iter()
      .flat_map(|(f, e)| f..e)
      .take(MAX_FRAGMENTS_NACKED)
  }
}

// Assembles fragments from a single (remote) Writer
// So there is only one sequence of SNs
pub(crate) struct FragmentAssembler {
  assembly_buffers: BTreeMap<SequenceNumber, AssemblyBuffer>,
  // Whether the owning reader is Reliable. This decides which sample to drop
  // when `max_open_samples_per_writer` is reached (see `new_datafrag_within`).
  reliable: bool,
}

impl fmt::Debug for FragmentAssembler {
  fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
    f.debug_struct("FragmentAssembler - fields omitted")
      // insert field printing here, if you really need it.
      .finish()
  }
}

impl FragmentAssembler {
  /// The fragment size is taken per sample from its DATA_FRAGs.
  pub fn new(fragment_size: u16, reliable: bool) -> Self {
    debug!("new FragmentAssembler. frag_size = {fragment_size} reliable = {reliable}");
    Self {
      assembly_buffers: BTreeMap::new(),
      reliable,
    }
  }

  // Returns completed DDSData, when complete, and disposes the assembly buffer.
  pub fn new_datafrag(
    &mut self,
    datafrag: &DataFrag,
    flags: BitFlags<DATAFRAG_Flags>,
  ) -> Option<DDSData> {
    self.new_datafrag_within(datafrag, flags, &fragment_reassembly_limits())
  }

  fn new_datafrag_within(
    &mut self,
    datafrag: &DataFrag,
    flags: BitFlags<DATAFRAG_Flags>,
    limits: &FragmentReassemblyLimits,
  ) -> Option<DDSData> {
    let sn = datafrag.writer_sn;
    let run = match FragRun::of(datafrag, limits.max_sample_size) {
      Ok(run) => run,
      Err(why) => {
        log_dropped(sn, format_args!("{why}"));
        return None;
      }
    };

    if !self.assembly_buffers.contains_key(&sn) {
      // Make room for one more sample, or refuse this one.
      while self.assembly_buffers.len() >= limits.max_open_samples_per_writer {
        // Reliable: the reader delivers in order, so it must complete the lowest SN
        // first; dropping it could livelock against a writer that bursts ahead. The
        // writer resends what we drop. Best effort: a low incomplete SN is lost anyway.
        let evict = if self.reliable {
          self
            .assembly_buffers
            .last_key_value()
            .map(|(k, _)| *k)
            .filter(|k| *k > sn)
        } else {
          self
            .assembly_buffers
            .first_key_value()
            .map(|(k, _)| *k)
            .filter(|k| *k < sn)
        };
        let Some(evict) = evict else {
          // Routine for a writer that bursts ahead: it resends. Not logged as an error.
          debug!("DATA_FRAG of sample {sn:?} dropped: too many samples of its writer open");
          return None;
        };
        self.assembly_buffers.remove(&evict);
      }
      let Some(buffer) = AssemblyBuffer::new(&run, limits.max_buffered_bytes) else {
        log_dropped(
          sn,
          format_args!(
            "incomplete samples hold the limit of {} bytes",
            limits.max_buffered_bytes
          ),
        );
        return None;
      };
      self.assembly_buffers.insert(sn, buffer);
    }
    let assembly_buffer = self.assembly_buffers.get_mut(&sn)?;

    if !assembly_buffer.same_sample(&run) {
      log_dropped(
        sn,
        format_args!(
          "malformed: sample size {} / fragment size {} differ from its first fragment's",
          run.data_size, run.fragment_size
        ),
      );
      return None;
    }
    if !assembly_buffer.insert(
      &run,
      &datafrag.serialized_payload,
      limits.max_buffered_bytes,
    ) {
      log_dropped(
        sn,
        format_args!(
          "incomplete samples hold the limit of {} bytes",
          limits.max_buffered_bytes
        ),
      );
      if assembly_buffer.runs.is_empty() {
        self.assembly_buffers.remove(&sn);
      }
      return None;
    }

    if !assembly_buffer.is_complete() {
      debug!("new_dataFrag: FRAGMENT NOT COMPLETED YET");
      return None;
    }
    debug!("new_datafrag: COMPLETED FRAGMENT");
    let assembly_buffer = self.assembly_buffers.remove(&sn)?;
    let serialized_data_or_key = SerializedPayload::from_bytes(&assembly_buffer.assembled())
      .map_err(|e| error!("Deserializing SerializedPayload from DATAFRAG: {e:?}"))
      .ok()?;
    Some(if flags.contains(DATAFRAG_Flags::Key) {
      DDSData::new_disposed_by_key(ChangeKind::NotAliveDisposed, serialized_data_or_key)
    } else {
      DDSData::new(serialized_data_or_key)
    })
  }

  pub fn garbage_collect_before(&mut self, expire_before: Timestamp) {
    self.assembly_buffers.retain(|sn, ab| {
      let retain = ab.modified_time >= expire_before;
      if !retain {
        info!("AssemblyBuffer dropping {sn:?}");
      }
      retain
    });
  }

  /// No sample of this writer is being reassembled.
  pub fn is_empty(&self) -> bool {
    self.assembly_buffers.is_empty()
  }

  pub fn is_partially_received(&self, sn: SequenceNumber) -> bool {
    self.assembly_buffers.contains_key(&sn)
    // assembly buffers map contains a key (SN) if and only if we have some
    // frags but not all
  }

  pub fn missing_frags_for(
    &self,
    seq: SequenceNumber,
  ) -> Box<dyn '_ + Iterator<Item = FragmentNumber>> {
    match self.assembly_buffers.get(&seq) {
      None => Box::new(iter::empty()),
      Some(ab) => Box::new(ab.missing().map(|f| FragmentNumber::new(f + 1))),
    }
  }
}

#[cfg(test)]
mod tests {
  // cellsuite: the tests are rewritten for the new assembler (vendor/README.md, patch 4).
  use bytes::Bytes;
  use enumflags2::BitFlags;

  use super::{AssemblyBuffer, FragRun, FragmentAssembler, FragmentReassemblyLimits};
  use crate::{
    messages::submessages::submessages::{DATAFRAG_Flags, DataFrag},
    structure::sequence_number::{FragmentNumber, SequenceNumber},
  };

  // A DATAFRAG of sample `sn` carrying the contiguous run of `k` fragments
  // starting at 1-based `start`, with the given payload bytes.
  fn datafrag(
    sn: i64,
    start: u32,
    k: u16,
    frag_size: u16,
    data_size: u32,
    payload: &[u8],
  ) -> DataFrag {
    DataFrag {
      writer_sn: SequenceNumber::new(sn),
      fragment_starting_num: FragmentNumber::new(start),
      fragments_in_submessage: k,
      fragment_size: frag_size,
      data_size,
      serialized_payload: Bytes::copy_from_slice(payload),
      ..Default::default()
    }
  }

  // A sample: a CDR_LE encapsulation header, then counting bytes.
  fn sample(size: usize) -> Vec<u8> {
    let mut bytes: Vec<u8> = (0..size).map(|i| (i % 251) as u8).collect();
    bytes[..4].copy_from_slice(&[0, 1, 0, 0]);
    bytes
  }

  // The sample's bytes after the 4-byte header, if `frag` completed it.
  fn feed(
    fa: &mut FragmentAssembler,
    frag: &DataFrag,
    limits: &FragmentReassemblyLimits,
  ) -> Option<Bytes> {
    fa.new_datafrag_within(frag, BitFlags::<DATAFRAG_Flags>::empty(), limits)
      .map(|d| d.data())
  }

  fn open_samples(fa: &FragmentAssembler) -> Vec<i64> {
    fa.assembly_buffers
      .keys()
      .map(|sn| i64::from(*sn))
      .collect()
  }

  // A DATAFRAG that packs K > 1 fragments in one submessage must reassemble the
  // same bytes as one-fragment-per-submessage would.
  #[test]
  fn reassemble_multi_fragment_datafrag() {
    let limits = FragmentReassemblyLimits::default();
    let whole = sample(2600); // 3 fragments of 1024: 1024, 1024, 552
    let mut fa = FragmentAssembler::new(1024, true);
    assert_eq!(
      feed(
        &mut fa,
        &datafrag(1, 1, 2, 1024, 2600, &whole[..2048]),
        &limits
      ),
      None
    );
    let done = feed(
      &mut fa,
      &datafrag(1, 3, 1, 1024, 2600, &whole[2048..]),
      &limits,
    );
    assert_eq!(done.as_deref(), Some(&whole[4..]));
    assert!(fa.is_empty());
  }

  // Fragments out of order, resent, and resent with another packing.
  #[test]
  fn reassemble_out_of_order_and_overlapping_runs() {
    let limits = FragmentReassemblyLimits::default();
    let whole = sample(1000); // 10 fragments of 100
    let mut fa = FragmentAssembler::new(100, false);
    for (start, k) in [(9, 2), (2, 3), (3, 1), (1, 4), (9, 1)] {
      let bytes =
        &whole[(start as usize - 1) * 100..((start as usize - 1 + k as usize) * 100).min(1000)];
      assert_eq!(
        feed(&mut fa, &datafrag(7, start, k, 100, 1000, bytes), &limits),
        None
      );
    }
    let missing: Vec<u32> = fa
      .missing_frags_for(SequenceNumber::new(7))
      .map(u32::from)
      .collect();
    assert_eq!(missing, [5, 6, 7, 8]);
    let done = feed(
      &mut fa,
      &datafrag(7, 4, 5, 100, 1000, &whole[300..800]),
      &limits,
    );
    assert_eq!(done.as_deref(), Some(&whole[4..]));
  }

  // The last fragment may carry alignment padding beyond the sample's end.
  #[test]
  fn padding_after_the_last_fragment_is_ignored() {
    let limits = FragmentReassemblyLimits::default();
    let whole = sample(250);
    let mut padded = whole[200..].to_vec();
    padded.extend_from_slice(&[0xEE, 0xEE]);
    let mut fa = FragmentAssembler::new(100, true);
    assert_eq!(
      feed(
        &mut fa,
        &datafrag(1, 1, 2, 100, 250, &whole[..200]),
        &limits
      ),
      None
    );
    let done = feed(&mut fa, &datafrag(1, 3, 1, 100, 250, &padded), &limits);
    assert_eq!(done.as_deref(), Some(&whole[4..]));
  }

  // Issue 23: one DATA_FRAG announcing ~4 GiB was allocated (and zeroed) whole.
  #[test]
  fn a_sample_over_the_size_limit_is_dropped() {
    let limits = FragmentReassemblyLimits::default();
    let mut fa = FragmentAssembler::new(1024, true);
    for sn in 1..=1000 {
      let frag = datafrag(sn, 1, 1, 1024, 0xFFFF_FFF0, &[0; 1024]);
      assert_eq!(feed(&mut fa, &frag, &limits), None);
    }
    assert!(fa.is_empty());
  }

  // Under the size limit, memory follows the fragments that arrived, not the
  // announced size: even when the first fragment to arrive is the last one.
  #[test]
  fn memory_follows_the_fragments_received() {
    let limits = FragmentReassemblyLimits::default();
    let data_size = 60 << 20;
    let mut fa = FragmentAssembler::new(1024, true);
    let last = data_size / 1024;
    assert_eq!(
      feed(
        &mut fa,
        &datafrag(1, last, 1, 1024, data_size, &[7; 1024]),
        &limits
      ),
      None
    );
    assert_eq!(
      feed(
        &mut fa,
        &datafrag(1, 1, 1, 1024, data_size, &[7; 1024]),
        &limits
      ),
      None
    );
    let charged = fa.assembly_buffers.values().next().unwrap().charged;
    assert!(
      charged < 4096,
      "charged {charged} bytes for two fragments of 1024"
    );
    let missing = fa.missing_frags_for(SequenceNumber::new(1)).count();
    assert_eq!(missing, 256, "one NACK_FRAG's worth");
  }

  #[test]
  fn malformed_fragments_are_dropped() {
    let limits = FragmentReassemblyLimits::default();
    let mut fa = FragmentAssembler::new(256, true);
    let bad = [
      datafrag(1, 1, 1, 0, 512, &[]),                // fragment size 0
      datafrag(2, 1, 1, 256, 0, &[]),                // sample size 0
      datafrag(3, 1, 1, 1024, 512, &[0; 512]),       // fragment larger than sample
      datafrag(4, 0, 1, 256, 512, &[0; 256]),        // fragment number 0
      datafrag(5, 1, 0, 256, 512, &[]),              // no fragments
      datafrag(6, 2, 2, 256, 512, &[0; 256]),        // run beyond the last fragment
      datafrag(7, u32::MAX, 2, 256, 512, &[0; 256]), // run beyond u32
      datafrag(8, 1, 1, 256, 512, &[0; 100]),        // payload short
    ];
    for frag in &bad {
      assert_eq!(feed(&mut fa, frag, &limits), None);
    }
    assert!(fa.is_empty(), "open: {:?}", open_samples(&fa));

    // A fragment whose sizes differ from the first fragment of its sample.
    assert_eq!(
      feed(&mut fa, &datafrag(9, 1, 1, 256, 512, &[0; 256]), &limits),
      None
    );
    assert_eq!(
      feed(&mut fa, &datafrag(9, 2, 1, 256, 600, &[0; 256]), &limits),
      None
    );
    assert_eq!(fa.missing_frags_for(SequenceNumber::new(9)).count(), 1);
  }

  #[test]
  fn reliable_readers_keep_the_oldest_open_samples() {
    let limits = FragmentReassemblyLimits {
      max_open_samples_per_writer: 3,
      ..Default::default()
    };
    let mut fa = FragmentAssembler::new(100, true);
    for sn in [5, 6, 7, 8, 2] {
      feed(&mut fa, &datafrag(sn, 1, 1, 100, 300, &[0; 100]), &limits);
    }
    assert_eq!(open_samples(&fa), [2, 5, 6]);
  }

  #[test]
  fn best_effort_readers_keep_the_newest_open_samples() {
    let limits = FragmentReassemblyLimits {
      max_open_samples_per_writer: 3,
      ..Default::default()
    };
    let mut fa = FragmentAssembler::new(100, false);
    for sn in [5, 6, 7, 8, 2] {
      feed(&mut fa, &datafrag(sn, 1, 1, 100, 300, &[0; 100]), &limits);
    }
    assert_eq!(open_samples(&fa), [6, 7, 8]);
  }

  // The budget counts every incomplete sample of the process (other tests run
  // alongside and hold a few kB at most), so this one uses 100 kB fragments.
  #[test]
  fn incomplete_samples_stay_within_the_byte_budget() {
    let limits = FragmentReassemblyLimits {
      max_buffered_bytes: 1 << 20,
      ..Default::default()
    };
    let frag = vec![0; 100_000];
    let mut writers: Vec<FragmentAssembler> =
      (0..20).map(|_| FragmentAssembler::new(0, true)).collect();
    for fa in &mut writers {
      feed(
        fa,
        &datafrag(1, 1, 1, 50_000, 400_000, &frag[..50_000]),
        &limits,
      );
      feed(
        fa,
        &datafrag(1, 2, 1, 50_000, 400_000, &frag[..50_000]),
        &limits,
      );
    }
    let held: usize = writers
      .iter()
      .flat_map(|fa| fa.assembly_buffers.values())
      .map(|ab| ab.charged)
      .sum();
    assert!(held <= 1 << 20, "{held} bytes held");
    assert!(held > 500_000, "only {held} bytes held");
    assert!(writers[19].is_empty(), "the last writer found no room");
    writers.clear();
    // Released: a new sample fits again.
    let mut fa = FragmentAssembler::new(0, true);
    feed(
      &mut fa,
      &datafrag(1, 1, 1, 50_000, 400_000, &frag[..50_000]),
      &limits,
    );
    assert!(!fa.is_empty());
  }

  #[test]
  fn frag_run_byte_ranges() {
    let run = FragRun::of(&datafrag(1, 2, 2, 100, 250, &[0; 150]), 1000).unwrap();
    assert_eq!((run.first, run.end, run.fragment_count), (1, 3, 3));
    assert_eq!(run.byte_range(run.first, run.end), 100..250);
    let ab = AssemblyBuffer::new(&run, usize::MAX).unwrap();
    assert_eq!(ab.gaps(0, 3), [(0, 3)]);
  }
}
