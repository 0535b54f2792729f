//! A frame's profile: (pass, GPU ms, CPU ms) and the device memory its resources hold,
//! as a table for people and as Chrome trace-event JSON for Perfetto.

use std::fmt::Write as _;

use crate::renderer::Frame;

/// Median per pass over several frames (passes matched by name and order).
pub fn median_passes(frames: &[Frame]) -> Vec<crate::vk::PassTiming> {
    let Some(first) = frames.first() else { return Vec::new() };
    let med = |mut v: Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        if v.is_empty() {
            0.0
        } else {
            v[v.len() / 2]
        }
    };
    first
        .passes
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let same = |f: &&Frame| f.passes.get(i).is_some_and(|q| q.name == p.name);
            crate::vk::PassTiming {
                name: p.name.clone(),
                gpu_ms: med(frames.iter().filter(same).map(|f| f.passes[i].gpu_ms).collect()),
                cpu_ms: med(frames.iter().filter(same).map(|f| f.passes[i].cpu_ms).collect()),
                gpu_start_ms: med(frames.iter().filter(same).map(|f| f.passes[i].gpu_start_ms).collect()),
            }
        })
        .collect()
}

/// The per-pass table: one row per pass in recording order, consecutive passes of the same
/// name summed into one row `name ×N` (a planar mirror's views, the six faces of a cube),
/// then the frame's total and the device memory per resource.
pub fn table(passes: &[crate::vk::PassTiming], memory: &[(String, u64)]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{:<24} {:>10} {:>10}", "pass", "GPU ms", "CPU ms");
    let mut i = 0;
    while i < passes.len() {
        let run = passes[i..].iter().take_while(|p| p.name == passes[i].name).count();
        let (gpu, cpu): (f64, f64) = passes[i..i + run].iter().fold((0.0, 0.0), |(g, c), p| (g + p.gpu_ms, c + p.cpu_ms));
        let name = if run > 1 { format!("{} ×{run}", passes[i].name) } else { passes[i].name.clone() };
        let _ = writeln!(s, "{name:<24} {gpu:>10.3} {cpu:>10.3}");
        i += run;
    }
    let gpu: f64 = passes.iter().map(|p| p.gpu_ms).sum();
    let cpu: f64 = passes.iter().map(|p| p.cpu_ms).sum();
    let _ = writeln!(s, "{:<24} {:>10.3} {:>10.3}", "frame", gpu, cpu);
    let _ = writeln!(s, "\n{:<32} {:>12}", "device memory", "MiB");
    for (name, bytes) in memory {
        let _ = writeln!(s, "{:<32} {:>12.3}", name, *bytes as f64 / (1024.0 * 1024.0));
    }
    let total: u64 = memory.iter().map(|(_, b)| b).sum();
    let _ = writeln!(s, "{:<32} {:>12.3}", "total", total as f64 / (1024.0 * 1024.0));
    s
}

/// Chrome trace-event JSON (open in Perfetto or chrome://tracing): one complete event per
/// pass on a GPU track and one on a CPU-recording track, plus the memory as metadata.
pub fn chrome_trace(passes: &[crate::vk::PassTiming], memory: &[(String, u64)], device: &str) -> String {
    let mut events = Vec::new();
    events.push(serde_json::json!({"name": "process_name", "ph": "M", "pid": 1, "args": {"name": format!("specula on {device}")}}));
    events.push(serde_json::json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 1, "args": {"name": "GPU"}}));
    events.push(serde_json::json!({"name": "thread_name", "ph": "M", "pid": 1, "tid": 2, "args": {"name": "CPU recording"}}));
    let mut cpu_t = 0.0;
    for p in passes {
        events.push(serde_json::json!({"name": p.name, "cat": "gpu", "ph": "X", "pid": 1, "tid": 1, "ts": p.gpu_start_ms * 1e3, "dur": p.gpu_ms * 1e3}));
        events.push(
            serde_json::json!({"name": p.name, "cat": "cpu", "ph": "X", "pid": 1, "tid": 2, "ts": cpu_t * 1e3, "dur": p.cpu_ms * 1e3}),
        );
        cpu_t += p.cpu_ms;
    }
    let mem: serde_json::Map<String, serde_json::Value> = memory.iter().map(|(n, b)| (n.clone(), serde_json::json!(b))).collect();
    let total: u64 = memory.iter().map(|(_, b)| b).sum();
    serde_json::to_string_pretty(&serde_json::json!({
        "traceEvents": events,
        "displayTimeUnit": "ms",
        "otherData": {"device": device, "device_memory_bytes": mem, "device_memory_total_bytes": total},
    }))
    .unwrap_or_default()
}

#[cfg(test)]
mod tests {
    use crate::vk::PassTiming;

    #[test]
    fn consecutive_passes_of_one_name_share_a_row() {
        let p = |name: &str, gpu_ms: f64| PassTiming { name: name.into(), gpu_ms, cpu_ms: 0.5, gpu_start_ms: 0.0 };
        let passes = [p("a", 1.0), p("v", 2.0), p("v", 3.0), p("b", 4.0), p("v", 5.0)];
        let t = super::table(&passes, &[]);
        let rows: Vec<&str> = t.lines().skip(1).take(4).collect();
        assert!(rows[0].starts_with("a ") && rows[1].starts_with("v ×2") && rows[1].contains("5.000"), "{t}");
        assert!(rows[2].starts_with("b ") && rows[3].starts_with("v ") && rows[3].contains("5.000"), "{t}");
        assert!(t.lines().any(|l| l.starts_with("frame") && l.contains("15.000")), "{t}");
    }
}
