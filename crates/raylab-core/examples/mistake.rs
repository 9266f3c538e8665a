//! Renders the lab's figure as a classic mistake would, to see what the mistake looks like or
//! to try `raylab check` on (docs/check.md).
//!
//! ```text
//! cargo run --release -p raylab-core --example mistake -- NAME OUT.png [STAGE] [W H]
//! ```
//!
//! NAME is a mistake of `raylab check`'s catalogue (`inverse-r`, `shadow-acne`, `gamma`, …),
//! STAGE one of the lab's (default `lab`), W × H the size (default 512 × 512).

use raylab_core::shapes::scene::cornell_box;
use raylab_core::teaching::check::{Mistake, mistakes::looks};
use raylab_core::{RenderSettings, Shading, Stage};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [name, out, rest @ ..] = args.as_slice() else {
        let names: Vec<&str> = Mistake::catalogue().map(Mistake::name).collect();
        return Err(format!(
            "usage: mistake NAME OUT.png [STAGE] [W H]; NAME: {}",
            names.join(", ")
        )
        .into());
    };
    let mistake: Mistake = name.parse()?;
    let stage: Stage = rest.first().map_or(Ok(Stage::Lab), |s| s.parse())?;
    let (width, height) = match rest {
        [_, w, h, ..] => (w.parse()?, h.parse()?),
        _ => (512, 512),
    };
    let mut settings = RenderSettings::default();
    settings.camera = settings.camera.with_resolution(width, height);
    settings.shading = Shading::for_stage(stage);
    settings.validate()?;
    if !mistake.applies(&settings) {
        return Err(format!("{name} does not change the {stage} stage's figure").into());
    }
    looks(&cornell_box(), &settings, mistake)[0]
        .to_image()
        .save(std::path::Path::new(out))?;
    println!("{name} at the {stage} stage, {width}×{height} → {out}");
    Ok(())
}
