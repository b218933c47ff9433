pub mod fit;
pub mod inspect;
pub mod micro;
pub mod pixel;
pub mod tangle;
pub mod texture;
pub mod texture_index;

use filigree::core::job::{run_to_end, Cancel, Job};
use filigree::Error;
use serde::{de::DeserializeOwned, Serialize};
use serde_json::Value;
use std::path::Path;

/// Read a file, naming it in the error.
pub fn read_file(path: &Path) -> Result<Vec<u8>, String> {
    std::fs::read(path).map_err(|e| format!("{}: {e}", path.display()))
}

/// `text` without a leading UTF-8 byte order mark (editors on Windows
/// write one; JSON readers refuse it).
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// `text` cut to 40 characters for a message (a 309-digit number is not
/// worth echoing in full).
pub fn short(text: &str) -> String {
    const MAX: usize = 40;
    if text.chars().count() <= MAX {
        text.to_string()
    } else {
        format!("{}…", text.chars().take(MAX).collect::<String>())
    }
}

/// Check an output path before any work starts: its extension is one of
/// `kinds` (lower case, without the dot; the first is what the error
/// suggests) and its folder exists, so a long run never ends in a write that
/// fails. Returns the extension.
pub fn out_path(path: &Path, kinds: &[&str]) -> Result<String, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    if !kinds.contains(&ext.as_str()) {
        let names: Vec<String> = kinds.iter().map(|k| format!(".{k}")).collect();
        return Err(format!(
            "{}: this output is written as {}; name the file with {}",
            path.display(),
            kinds.join(" or ").to_ascii_uppercase(),
            names.join(" or ")
        ));
    }
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if !dir.is_dir() {
        return Err(format!(
            "{}: the folder {} does not exist",
            path.display(),
            dir.display()
        ));
    }
    if path.is_dir() {
        return Err(format!("{}: is a folder, not a file", path.display()));
    }
    Ok(ext)
}

/// Read and decode an image file with the default limits, naming the file in errors.
#[allow(dead_code)] // used by the tool subcommands
pub fn read_image(path: &Path) -> Result<filigree::raster::Rgba8Image, String> {
    let bytes = read_file(path)?;
    filigree::raster::decode(&bytes, filigree::raster::Limits::default())
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// Where a request field came from on the command line: `(field, what)`,
/// e.g. `("params.d_max", "--dmax")` or `("source", "fish.png")`. The
/// longest matching prefix of an error's field wins; a field with no entry
/// is named as the flag `--<first segment>`.
pub type Origins = Vec<(&'static str, String)>;

/// A core error as a CLI message: what (flag or file) it is about, then the message.
pub fn explain(e: Error, origins: &Origins) -> String {
    let Some(field) = e.field() else {
        return e.to_string();
    };
    let segs: Vec<&str> = field.split('.').collect();
    let which = (1..=segs.len())
        .rev()
        .find_map(|n| {
            let prefix = segs[..n].join(".");
            origins
                .iter()
                .find(|(k, _)| *k == prefix)
                .map(|(_, v)| v.clone())
        })
        .unwrap_or_else(|| format!("--{}", segs[0].replace('_', "-")));
    format!("{which}: {e}")
}

/// Build a request from the flags that were given (a JSON object with the
/// request's field names): missing fields take the request's defaults,
/// exactly as a browser payload does.
pub fn request<T: DeserializeOwned>(
    kind: &str,
    flags: Value,
    origins: &Origins,
) -> Result<T, String> {
    // The flag already says where; the request kind would only repeat it.
    filigree::api::request(kind, flags)
        .map_err(|e| explain(e, origins).replacen(&format!("{kind}: "), "", 1))
}

/// `--print-request`: the request as JSON on stdout (what the browser would send).
pub fn print_request<T: Serialize>(req: &T) -> Result<(), String> {
    println!("{}", serde_json::to_string(req).map_err(|e| e.to_string())?);
    Ok(())
}

/// Drive a core job to its end, printing progress to stderr unless `quiet`.
pub fn drive<J: Job>(job: J, quiet: bool, origins: &Origins) -> Result<J::Output, String> {
    let mut last = -1.0;
    run_to_end(job, &Cancel::new(), |p| {
        if !quiet && p.fraction - last >= 0.05 {
            last = p.fraction;
            match p.figure {
                Some(f) => eprintln!("{:>3.0}%  {}  best {f:.5}", p.fraction * 100.0, p.stage),
                None => eprintln!("{:>3.0}%  {}", p.fraction * 100.0, p.stage),
            }
        }
    })
    .map_err(|e| explain(e, origins))
}

/// Insert `key: value` into a JSON object when the flag was given
/// (`flag` names it in errors: JSON has no NaN or infinity).
pub fn put<T: Serialize>(
    obj: &mut serde_json::Map<String, Value>,
    key: &str,
    flag: &str,
    v: Option<T>,
) -> Result<(), String> {
    if let Some(v) = v {
        let j = serde_json::to_value(v).map_err(|e| format!("{flag}: {e}"))?;
        if j.is_null() {
            return Err(format!("{flag}: must be a finite number"));
        }
        obj.insert(key.to_string(), j);
    }
    Ok(())
}

/// Print `value` as pretty JSON on stdout (what `--json` and `bench` print).
pub fn print_json(value: &impl Serialize) -> Result<(), String> {
    println!(
        "{}",
        serde_json::to_string_pretty(value).map_err(|e| e.to_string())?
    );
    Ok(())
}

/// `--threads`: the asked number when in range, else all cores
/// ([`filigree::core::parallel::threads`]).
pub fn threads(asked: Option<usize>) -> Result<usize, String> {
    filigree::core::parallel::threads(asked).map_err(|e| format!("--threads: {e}"))
}
