//! Draws a battery's detection-limit sheet (rig_virtual_rig::battery::detection_sheet)
//! from its `confusion-detection.csv`, as the full-battery test and the
//! `confusion` stage write it, without rerunning the battery:
//! `cargo run -p rig-virtual-rig --example battery_figure -- DIR [BATTERY_NAME]`
//! writes DIR/battery-detection.{svg,png,csv}.

use rig_types::Table;
use rig_virtual_rig::battery::detection_sheet;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let dir = args.next().ok_or("usage: battery_figure DIR [BATTERY_NAME]")?;
    let name = args.next().unwrap_or_else(|| "full".into());
    let path = format!("{dir}/confusion-detection.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{path}: {e}"))?;
    let mut lines = text.lines();
    let mut t = Table::new(lines.next().ok_or(format!("{path}: empty"))?.split(','));
    for (k, line) in lines.enumerate() {
        let row: Vec<&str> = line.split(',').collect();
        if row.len() != t.columns.len() {
            return Err(format!("{path}:{}: {} fields, the header has {}", k + 2, row.len(), t.columns.len()).into());
        }
        t.push(row);
    }
    let sheet = detection_sheet(&t, &name).ok_or(format!("{path}: no ladder rows"))?;
    std::fs::write(format!("{dir}/battery-detection.svg"), rig_figures::render_sheet_svg(&sheet)?)?;
    std::fs::write(format!("{dir}/battery-detection.png"), rig_figures::render_sheet_png(&sheet)?)?;
    std::fs::write(format!("{dir}/battery-detection.csv"), rig_figures::sheet_csv(&sheet))?;
    Ok(())
}
