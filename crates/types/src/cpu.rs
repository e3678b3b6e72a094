//! The process's CPU time, for the timings the pipeline writes and the
//! examples that measure a stage or a battery case (one home: issue 26's
//! "one home per idea").

/// CPU time (user + system) of this process so far, s, from /proc/self/stat
/// (Linux; clock ticks of 10 ms). `None` elsewhere.
pub fn process_cpu_s() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name: state is field 3, utime 14, stime 15.
    let fields: Vec<&str> = stat.rsplit(')').next()?.split_whitespace().collect();
    let ticks = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}
