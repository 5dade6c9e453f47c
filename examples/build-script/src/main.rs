//! Includes the variant the build script wrote and shows what running it
//! takes: its passes, per pass the targets and depth state, and the
//! bindings the host must supply.

use shadecache::plan::Plan;

const PLAN: &str = shadecache::include_variant!("noise_marble", "nb0c12cc4", "three-pass", "plan.json");
const PASSES: [&str; 3] = [
    shadecache::include_variant!("noise_marble", "nb0c12cc4", "three-pass", "pass1.wgsl"),
    shadecache::include_variant!("noise_marble", "nb0c12cc4", "three-pass", "pass2.wgsl"),
    shadecache::include_variant!("noise_marble", "nb0c12cc4", "three-pass", "pass3.wgsl"),
];

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let plan: Plan = serde_json::from_str(PLAN)?;
    println!(
        "{} caches `{}` ({}) with {} passes:",
        plan.shader,
        plan.node.text,
        plan.variant,
        plan.passes.len()
    );
    for (pass, source) in plan.passes.iter().zip(PASSES) {
        // The generated WGSL is ready for wgpu; parse it here to show it is.
        let module = naga::front::wgsl::parse_str(source)?;
        let targets: Vec<String> = pass
            .color_targets
            .iter()
            .map(|t| format!("@location({}) {} {}", t.location, t.target, t.format))
            .collect();
        println!(
            "  {}: {} entry points; depth {} (write {}); targets {}",
            pass.name,
            module.entry_points.len(),
            pass.depth.compare,
            pass.depth.write,
            targets.join(", ")
        );
    }
    for twin in &plan.bindings.previous {
        println!(
            "  group {} binding {}: last frame's `{}`",
            twin.group, twin.binding, twin.shadows.name
        );
    }
    Ok(())
}
