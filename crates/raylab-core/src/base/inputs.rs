//! Reading the files raylab is given: regular files only, each kind with a cap on its size.
//!
//! A path may name anything: a FIFO, whose reader waits for a writer that may never come (the
//! window would never appear), a device such as `/dev/zero`, which never ends, or a file far
//! larger than any real one of its kind. Every file raylab reads — scene files, settings,
//! screenshots, OBJ models, their material libraries and textures — is opened with
//! [`open_regular`], which refuses anything but a regular file without waiting, and read with
//! [`read_capped`] under its kind's cap below. Each refusal is one line naming what the file is
//! and the cap.

use std::fs::File;
use std::io::Read as _;
use std::path::{Path, PathBuf};

use crate::base::memory::format_bytes;

/// The largest scene file (`.toml`) or settings JSON read: 4 MiB. Raylab writes them in a few
/// KiB; a hand-written scene with many models stays far below.
pub const MAX_SCENE_FILE_BYTES: u64 = 4 << 20;

/// The largest settings text a screenshot PNG may carry, after inflating it if it is
/// compressed: 1 MiB (raylab writes a few KiB).
pub const MAX_SETTINGS_TEXT_BYTES: u64 = 1 << 20;

/// The largest OBJ file read: 512 MiB, some ten million triangles. Loading takes about 8 bytes
/// of memory a byte of text ([`crate::shapes::scene::SceneSpec::memory_estimate`]), 4 GiB at the cap.
pub const MAX_OBJ_BYTES: u64 = 512 << 20;

/// The largest material library (`.mtl`) read: 16 MiB, some hundred thousand materials.
pub const MAX_MTL_BYTES: u64 = 16 << 20;

/// The largest texture file (PNG or JPEG) read: 512 MiB, more than an uncompressed 8-bit
/// 8192² image. What it decodes to is bounded by its sides
/// ([`crate::shading::texture::TextureImage::MAX_SIDE`]) and counted in the memory estimate.
pub const MAX_TEXTURE_FILE_BYTES: u64 = 512 << 20;

/// Opens `path` for reading if it is a regular file (following symbolic links), with its
/// length; anything else is refused at once, saying what it is. A FIFO is opened without
/// waiting for a writer (`O_NONBLOCK`), then refused.
pub fn open_regular(path: &Path) -> Result<(File, u64), String> {
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt as _;
        // Only changes how a FIFO or device opens; reads of regular files ignore it.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| e.to_string())?;
    let metadata = file.metadata().map_err(|e| e.to_string())?;
    if !metadata.is_file() {
        return Err(format!(
            "it is not a regular file ({})",
            kind_of(&metadata.file_type())
        ));
    }
    Ok((file, metadata.len()))
}

/// A size for a refusal, exact: `900 bytes`, or `4,195,204 bytes (4 MiB)` from a KiB on (the
/// rounded size alone would call a file a few bytes over a cap the cap's size).
pub fn exact_size(bytes: u64) -> String {
    let digits = bytes.to_string();
    let mut grouped = String::with_capacity(digits.len() + digits.len() / 3);
    for (i, digit) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            grouped.push(',');
        }
        grouped.push(digit);
    }
    if bytes < 1024 {
        format!("{grouped} bytes")
    } else {
        format!("{grouped} bytes ({})", format_bytes(bytes))
    }
}

/// What a file that is not a regular file is, in words.
fn kind_of(t: &std::fs::FileType) -> &'static str {
    if t.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt as _;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
    }
    "not a file"
}

/// The whole content of the regular file `path`, refused if it is more than `limit` bytes
/// (`what` names the kind of file in that refusal: "an OBJ file"). The error is the reason
/// alone; the caller names the file.
pub fn read_capped(path: &Path, limit: u64, what: &str) -> Result<Vec<u8>, String> {
    let (file, len) = open_regular(path)?;
    read_open(file, len, limit, what)
}

/// [`read_capped`] for a file [`open_regular`] opened (`len` its length then), read from
/// where it stands.
pub fn read_open(
    file: impl std::io::Read,
    len: u64,
    limit: u64,
    what: &str,
) -> Result<Vec<u8>, String> {
    let too_large = |size: &str| {
        format!(
            "it is {size}, more than the {} {what} may be",
            exact_size(limit)
        )
    };
    if len > limit {
        return Err(too_large(&exact_size(len)));
    }
    let mut bytes = Vec::new();
    bytes.try_reserve_exact(len as usize).map_err(|_| {
        format!(
            "it is {}, more than can be held in memory",
            format_bytes(len)
        )
    })?;
    // A file that grows while it is read is still read no further than the cap.
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| e.to_string())?;
    if bytes.len() as u64 > limit {
        return Err(too_large("growing"));
    }
    Ok(bytes)
}

/// A file a render or a check reads, and what it is to it ("a model", "the image to check"):
/// what no output of theirs may replace ([`refuse_output_onto`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Input {
    pub path: PathBuf,
    pub what: &'static str,
}

impl Input {
    pub fn new(path: &Path, what: &'static str) -> Self {
        Self {
            path: path.to_path_buf(),
            what,
        }
    }
}

/// Whether `a` and `b` name one file: the same device and inode (symbolic links followed, so
/// a link and its target, and two hard links, are one file) when both exist; otherwise the
/// same entry of the same folder, each folder resolved (`./x.png` and `sub/../x.png` are one).
pub fn same_file(a: &Path, b: &Path) -> bool {
    if let (Ok(x), Ok(y)) = (std::fs::metadata(a), std::fs::metadata(b)) {
        #[cfg(unix)]
        {
            use std::os::unix::fs::MetadataExt as _;
            return x.dev() == y.dev() && x.ino() == y.ino();
        }
        #[cfg(not(unix))]
        {
            let _ = (x, y);
            return std::fs::canonicalize(a).ok() == std::fs::canonicalize(b).ok();
        }
    }
    let entry = |p: &Path| -> Option<PathBuf> {
        let folder = match p.parent() {
            Some(dir) if !dir.as_os_str().is_empty() => dir,
            _ => Path::new("."),
        };
        Some(std::fs::canonicalize(folder).ok()?.join(p.file_name()?))
    };
    match (entry(a), entry(b)) {
        (Some(x), Some(y)) => x == y,
        _ => false,
    }
}

/// Refuses to write `output` (given as `option`: `--out`) where it would replace, or write
/// through, one of `inputs` ([`same_file`]): `reader` ("the render") would destroy a file it
/// reads. The error names the option, the file and what it is.
pub fn refuse_output_onto(
    option: &str,
    output: &Path,
    reader: &str,
    inputs: &[Input],
) -> Result<(), String> {
    match inputs.iter().find(|input| same_file(output, &input.path)) {
        None => Ok(()),
        Some(input) => Err(format!(
            "{option} '{}' is a file {reader} reads ({}: '{}'); writing there would replace it, \
             so choose another name",
            output.display(),
            input.what,
            input.path.display()
        )),
    }
}

/// Makes a FIFO at `path`, for tests of what refuses one.
#[cfg(unix)]
#[doc(hidden)]
pub fn make_fifo(path: &Path) {
    use std::os::unix::ffi::OsStrExt as _;
    let c = std::ffi::CString::new(path.as_os_str().as_bytes()).expect("no NUL in the path");
    // SAFETY: a valid NUL-terminated path; mkfifo reads it and nothing else.
    let made = unsafe { libc::mkfifo(c.as_ptr(), 0o600) };
    assert_eq!(made, 0, "mkfifo {}", path.display());
}

/// Text from a file made safe to print on a terminal: each control character (C0, DEL, C1:
/// escape sequences, carriage returns, line breaks) and each character that reorders the text
/// around it (bidirectional overrides and isolates) is written as its Rust escape, `\u{1b}`.
/// The command line passes everything it prints through this, so a scene's name or a file's
/// own name cannot move the cursor, recolour the terminal or split a one-line message; the
/// rest of the text is unchanged, and escaping twice changes nothing more.
pub fn escape_control(text: &str) -> std::borrow::Cow<'_, str> {
    let unsafe_char =
        |c: char| c.is_control() || matches!(c, '\u{202a}'..='\u{202e}' | '\u{2066}'..='\u{2069}');
    if !text.chars().any(unsafe_char) {
        return std::borrow::Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len() + 8);
    for c in text.chars() {
        if unsafe_char(c) {
            out.push_str(&format!("\\u{{{:x}}}", u32::from(c)));
        } else {
            out.push(c);
        }
    }
    std::borrow::Cow::Owned(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn control_characters_are_escaped_and_the_rest_kept() {
        assert_eq!(escape_control("figure 7 ρ·(D + N)"), "figure 7 ρ·(D + N)");
        assert_eq!(
            escape_control("\u{1b}[31mred\u{1b}[0m\r\nnext\u{7}\u{9b}\u{202e}"),
            "\\u{1b}[31mred\\u{1b}[0m\\u{d}\\u{a}next\\u{7}\\u{9b}\\u{202e}"
        );
        let once = escape_control("a\u{1b}b").into_owned();
        assert_eq!(escape_control(&once), once, "idempotent");
    }

    #[test]
    fn only_regular_files_within_their_cap_are_read() {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join("a.txt");
        std::fs::write(&file, "12345").unwrap();
        assert_eq!(read_capped(&file, 5, "a test file").unwrap(), b"12345");
        assert_eq!(
            read_capped(&file, 4, "a test file").unwrap_err(),
            "it is 5 bytes, more than the 4 bytes a test file may be"
        );
        // A few bytes over a cap of MiBs: the exact sizes, not "4 MiB, more than the 4 MiB".
        let over = dir.path().join("over.toml");
        std::fs::write(&over, vec![b'#'; (4 << 20) + 900]).unwrap();
        assert_eq!(
            read_capped(&over, MAX_SCENE_FILE_BYTES, "a scene file").unwrap_err(),
            "it is 4,195,204 bytes (4 MiB), more than the 4,194,304 bytes (4 MiB) a scene \
             file may be"
        );
        assert_eq!(exact_size(1023), "1,023 bytes");
        assert_eq!(exact_size(1024), "1,024 bytes (1 KiB)");
        assert_eq!(exact_size(123_456_789), "123,456,789 bytes (118 MiB)");
        assert_eq!(
            read_capped(dir.path(), 4, "x").unwrap_err(),
            "it is not a regular file (a folder)"
        );
        assert!(read_capped(&dir.path().join("none"), 4, "x").is_err());
        #[cfg(unix)]
        {
            // A device that never ends, and a FIFO nobody writes to: refused at once.
            assert_eq!(
                read_capped(Path::new("/dev/zero"), 4, "x").unwrap_err(),
                "it is not a regular file (a character device)"
            );
            let fifo = dir.path().join("fifo");
            make_fifo(&fifo);
            assert_eq!(
                read_capped(&fifo, 4, "x").unwrap_err(),
                "it is not a regular file (a FIFO)"
            );
            // A link to a regular file is read.
            let link = dir.path().join("link");
            std::os::unix::fs::symlink(&file, &link).unwrap();
            assert_eq!(read_capped(&link, 5, "x").unwrap(), b"12345");
        }
    }
}
