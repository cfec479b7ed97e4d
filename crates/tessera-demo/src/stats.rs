//! What each frame reports: the panel's live figures and `--stats-json`'s rows.

use std::collections::VecDeque;
use std::path::Path;
use std::time::Duration;

use serde::Serialize;

/// One frame's figures (a row of `--stats-json`).
#[derive(Clone, Debug, Default, Serialize)]
pub struct FrameStats {
    pub frame: u32,
    /// Of the drawn output, from the newest status that has arrived.
    pub triangles: u32,
    pub vertices: u32,
    pub patches: usize,
    /// Catmull-Clark adaptive: the largest leaf bound, model units; else null.
    pub guaranteed_bound: Option<f64>,
    /// Catmull-Clark adaptive in pixels: the tolerance, pixels; else null.
    pub tolerance_px: Option<f64>,
    /// Catmull-Clark adaptive in pixels: patches wholly out of view; else null.
    pub culled_patches: Option<u32>,
    /// The newest run's GPU time from timestamp queries, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_ms: Option<f64>,
    /// Where there are no timestamps, or on the CPU: the newest run's wall time, ms.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wall_ms: Option<f64>,
    /// This frame, from its start to its present (scripted: to the GPU finishing it).
    pub frame_ms: f64,
    /// Reallocations of the drawn stage's buffers so far.
    pub growths: u32,
    /// Whether this frame recorded a tessellation.
    pub tessellated: bool,
    /// The newest run overflowed its buffers: nothing is drawn until the rerun.
    #[serde(skip)]
    pub overflowed: bool,
}

/// Frame rate over the last second of frames.
#[derive(Default)]
pub struct FrameRate {
    intervals: VecDeque<Duration>,
}

impl FrameRate {
    pub fn push(&mut self, interval: Duration) {
        self.intervals.push_back(interval);
        while self.intervals.iter().sum::<Duration>() > Duration::from_secs(1)
            && self.intervals.len() > 1
        {
            self.intervals.pop_front();
        }
    }

    pub fn fps(&self) -> Option<f64> {
        let total: Duration = self.intervals.iter().sum();
        (!self.intervals.is_empty() && total > Duration::ZERO)
            .then(|| self.intervals.len() as f64 / total.as_secs_f64())
    }
}

/// Writes the rows as a JSON array.
pub fn write_json(path: &Path, rows: &[FrameStats]) -> Result<(), String> {
    let json =
        serde_json::to_string_pretty(rows).map_err(|e| format!("{}: {e}", path.display()))?;
    std::fs::write(path, json + "\n").map_err(|e| format!("{}: {e}", path.display()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_names_its_time_by_how_it_was_measured() {
        let gpu = FrameStats {
            gpu_ms: Some(1.5),
            ..Default::default()
        };
        let v = serde_json::to_value(&gpu).expect("json");
        assert_eq!(v["gpu_ms"], 1.5);
        assert!(v.get("wall_ms").is_none());
        for key in [
            "frame",
            "triangles",
            "vertices",
            "patches",
            "guaranteed_bound",
            "frame_ms",
            "growths",
            "tessellated",
        ] {
            assert!(v.get(key).is_some(), "{key}");
        }
    }

    #[test]
    fn the_rate_counts_the_last_second() {
        let mut r = FrameRate::default();
        assert_eq!(r.fps(), None);
        for _ in 0..100 {
            r.push(Duration::from_millis(20));
        }
        assert!((r.fps().expect("fps") - 50.0).abs() < 1.5);
    }
}
