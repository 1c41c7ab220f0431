//! One `.rrd` from several: every node of a `cell demo` run writes its own Rerun file (a
//! process cannot share another's file), all under one recording id; merging them gives the
//! single `cell.rrd` a viewer opens as the whole run.

use std::path::Path;

use anyhow::Context as _;

/// Merges every `.rrd` in `dir` (sorted by name) into `out`, written atomically; returns the
/// number of messages. The messages keep their recording ids, so nodes of one run stay one
/// recording.
///
/// # Errors
/// A directory or file that cannot be read, a file that is not a valid `.rrd`, or `out` not
/// writable.
pub fn merge_dir(dir: &Path, out: &Path) -> anyhow::Result<usize> {
    let mut inputs: Vec<_> = std::fs::read_dir(dir)
        .with_context(|| dir.display().to_string())?
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "rrd"))
        .collect();
    inputs.sort();
    anyhow::ensure!(!inputs.is_empty(), "no .rrd files in {}", dir.display());
    let mut encoder = re_log_encoding::Encoder::local()?;
    let mut count = 0;
    for path in &inputs {
        let reader = std::io::BufReader::new(
            std::fs::File::open(path).with_context(|| path.display().to_string())?,
        );
        let messages = re_log_encoding::DecoderApp::decode_eager(reader)
            .with_context(|| format!("{} is not a valid .rrd", path.display()))?;
        for message in messages {
            let message = message.with_context(|| path.display().to_string())?;
            encoder.append(&message)?;
            count += 1;
        }
    }
    encoder.finish()?;
    let bytes = encoder.into_inner()?;
    let tmp = out.with_extension("rrd.tmp");
    std::fs::write(&tmp, bytes).with_context(|| tmp.display().to_string())?;
    std::fs::rename(&tmp, out).with_context(|| out.display().to_string())?;
    Ok(count)
}
