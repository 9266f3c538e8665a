//! The `raylab` binary: the workbench window and the command line, thin layers over the library.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}

/// `raylab` with no command. Until the workbench window lands, this renders figure 7 to a PNG
/// and says so.
fn start_workbench() -> anyhow::Result<()> {
    let out = std::path::Path::new("raylab-figure7.png");
    let settings = raylab::RenderSettings::default();
    let image = raylab::render::render(&raylab::scene::cornell_box(), &settings);
    image.save(out)?;
    println!(
        "The workbench window is not built yet: rendered the lab's figure 7 to {}",
        out.display()
    );
    Ok(())
}
