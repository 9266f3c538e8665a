//! Makes a class's folder of submissions for `raylab check FOLDER` (docs/check.md, "A whole
//! class at once"): every mistake of the catalogue, right, anti-aliased and JPEG images, a truncated
//! PNG, an empty file, a text file, an image of the wrong size, a file the list leaves out and
//! identical images, with the list of what each is checked against.
//!
//! ```text
//! cargo run --release --example class_folder -- OUT [SIDE] [COUNT]
//! raylab check OUT/submissions --csv OUT/list.csv --report OUT/report
//! ```
//!
//! SIDE is the images' side (default 512); COUNT the submissions (default: the set once; more
//! repeats it, each round's pixels a level apart from the others', within the check's
//! tolerance).

#[path = "../tests/common/class_folder.rs"]
mod class_folder;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(out) = args.first() else {
        return Err("usage: class_folder OUT [SIDE] [COUNT]".into());
    };
    let side: u32 = args.get(1).map_or(Ok(512), |s| s.parse())?;
    let count: Option<usize> = args.get(2).map(|s| s.parse()).transpose()?;
    let root = std::path::Path::new(out);
    std::fs::create_dir_all(root)?;
    let (folder, list, made) = class_folder::make_class(root, side, count);
    println!(
        "{} submissions of {side}² in {}, listed in {}",
        made.len(),
        folder.display(),
        list.display()
    );
    Ok(())
}
