//! hexsim's limits on the work and memory an input may ask for, checked before the work starts
//! (docs/running.md, "Limits"): the size of each file read, the nesting of a URDF's XML, the
//! steps of a run and the iterations of one, threads. Each refusal names the number and the limit.

use std::io::{self, Read};
use std::path::Path;

/// The most bytes read from a text input: a URDF, its robot file, a gait, terrain, scenario,
/// comparison or optimisation file. The largest URDF measured (10,000 links) is 4 MB.
pub const TEXT_FILE_BYTES: u64 = 64 << 20;

/// The most bytes read from a terrain's data file (CSV, STL): a CSV of the largest grid
/// ([`crate::terrain::MAX_SAMPLES`] heights) at 16 characters a height.
pub const DATA_FILE_BYTES: u64 = 1 << 30;

/// The longest line of a CSV height file: a row of 65,536 heights at 16 characters each.
pub const CSV_LINE_BYTES: u64 = 1 << 20;

/// The deepest nesting of XML elements in a URDF (a URDF's is 4 or 5): a deeper one would
/// overflow the XML parser's stack.
pub const XML_DEPTH: usize = 100;

/// The most steps a run may take, (settle + duration) / dt: 10⁹ steps is some 14 hours of a
/// hex18 walk at 20,000 steps a second.
pub const MAX_STEPS: f64 = 1e9;

/// The smallest time step hexsim chooses for a walk (1 ms / 100): a smaller one means a robot
/// or gait whose numbers are out of scale (a mass of 10³⁰⁸ kg, a period of 10⁻⁹ s).
pub const MIN_CHOSEN_DT: f64 = 1e-5;

/// The most solver (and PGS) iterations of one step; the default is 4.
pub const MAX_ITERATIONS: usize = 1000;

/// The most work of a generated terrain, in sums of one wave at one sample (a rough terrain's
/// waves × samples): 2³⁰, some 15 s on one core, is the default 16 waves on the largest grid.
pub const TERRAIN_WORK: f64 = (1u64 << 30) as f64;

/// The most candidates a generation of `hexsim optimize` (CMA-ES's default for 10 parameters
/// is 10).
pub const MAX_POPULATION: usize = 10_000;

/// The most candidate evaluations of one search (generations × population).
pub const MAX_EVALUATIONS: f64 = 1e6;

/// The most worker threads (`-j`).
pub const MAX_THREADS: usize = 1024;

/// Reads a thread count (`-j`, `--jobs`): 1 to [`MAX_THREADS`].
pub fn threads(text: &str) -> Result<usize, String> {
    let n: usize = text
        .parse()
        .map_err(|_| format!("expected a number of threads, got {text:?}"))?;
    if (1..=MAX_THREADS).contains(&n) {
        Ok(n)
    } else {
        Err(format!("expected 1 to {MAX_THREADS} threads, got {n}"))
    }
}

/// Where a number read from a file must lie, besides being finite.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Range {
    Any,
    /// Above 0.
    Positive,
    /// At or above 0.
    NonNegative,
}

/// `v` finite and in `range`, else the one message every such field gives: "expected a finite
/// number > 0 s, got -1" (`unit` after the bound; empty for none).
pub fn check_number(v: f64, range: Range, unit: &str) -> Result<(), String> {
    let (ok, bound) = match range {
        Range::Any => (v.is_finite(), ""),
        Range::Positive => (v.is_finite() && v > 0.0, " > 0"),
        Range::NonNegative => (v.is_finite() && v >= 0.0, " ≥ 0"),
    };
    if ok {
        return Ok(());
    }
    let unit = if unit.is_empty() {
        String::new()
    } else {
        format!(" {unit}")
    };
    Err(format!("expected a finite number{bound}{unit}, got {v}"))
}

/// A number for a message, as short as it reads: 0.25, 43.7, 1e300, 1.2e-12.
pub fn num(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{}", (x * 1e4).round() / 1e4)
    } else {
        let text = format!("{x:.3e}");
        // 1.000e300 → 1e300, 1.200e-12 → 1.2e-12
        match text.split_once('e') {
            Some((mantissa, exponent)) => {
                let mantissa = mantissa.trim_end_matches('0').trim_end_matches('.');
                format!("{mantissa}e{exponent}")
            }
            None => text,
        }
    }
}

/// A count of bytes for a message: "64 MiB".
pub fn bytes(n: u64) -> String {
    match n {
        n if n >= 1 << 30 && n % (1 << 30) == 0 => format!("{} GiB", n >> 30),
        n if n >= 1 << 20 => format!("{} MiB", n >> 20),
        n => format!("{n} bytes"),
    }
}

fn too_large(limit: u64) -> io::Error {
    io::Error::new(
        io::ErrorKind::InvalidData,
        format!(
            "it is larger than {}, the most hexsim reads from such a file (is it the right file?)",
            bytes(limit)
        ),
    )
}

/// Reads at most `limit` bytes of `path`: a larger file (or an endless one, `/dev/zero`) is an
/// error naming the limit, after reading no more than `limit` + 1 bytes.
pub fn read(path: &Path, limit: u64) -> io::Result<Vec<u8>> {
    let file = std::fs::File::open(path)?;
    if let Ok(meta) = file.metadata()
        && meta.is_file()
        && meta.len() > limit
    {
        return Err(too_large(limit));
    }
    let mut data = Vec::new();
    file.take(limit + 1).read_to_end(&mut data)?;
    if data.len() as u64 > limit {
        return Err(too_large(limit));
    }
    Ok(data)
}

/// [`read`] as UTF-8 text.
pub fn read_to_string(path: &Path, limit: u64) -> io::Result<String> {
    String::from_utf8(read(path, limit)?).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!(
                "stream did not contain valid UTF-8 (at byte {})",
                e.utf8_error().valid_up_to()
            ),
        )
    })
}

/// A reader that fails once more than `limit` bytes in all, or a line longer than `line`
/// bytes, have come through it: a streamed file (a CSV) stays within bounded time and memory.
pub struct Bounded<R> {
    inner: R,
    limit: u64,
    line: u64,
    read: u64,
    since_newline: u64,
}

impl<R: Read> Bounded<R> {
    pub fn new(inner: R, limit: u64, line: u64) -> Self {
        Bounded {
            inner,
            limit,
            line,
            read: 0,
            since_newline: 0,
        }
    }
}

impl<R: Read> Read for Bounded<R> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.read += n as u64;
        if self.read > self.limit {
            return Err(too_large(self.limit));
        }
        let chunk = &buf[..n];
        match chunk.iter().rposition(|&b| b == b'\n') {
            Some(at) => self.since_newline = (n - at - 1) as u64,
            None => self.since_newline += n as u64,
        }
        let longest = chunk
            .split(|&b| b == b'\n')
            .map(|l| l.len() as u64)
            .max()
            .unwrap_or(0);
        if self.since_newline > self.line || longest > self.line {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!(
                    "a line is longer than {}, the longest hexsim reads (is it the right file?)",
                    bytes(self.line)
                ),
            ));
        }
        Ok(n)
    }
}

/// Checks that `text` (XML) nests its elements at most `max` deep, by a scan that reads tags,
/// comments, CDATA and processing instructions but builds nothing: a deeper document is refused
/// before a recursive parser overflows its stack. Returns the depth reached and the line.
pub fn xml_depth(text: &str, max: usize) -> Result<(), (usize, usize)> {
    let bytes = text.as_bytes();
    let mut depth = 0usize;
    let mut i = 0;
    let find = |from: usize, pattern: &[u8]| {
        bytes[from.min(bytes.len())..]
            .windows(pattern.len())
            .position(|w| w == pattern)
            .map(|p| from + p + pattern.len())
            .unwrap_or(bytes.len())
    };
    while i < bytes.len() {
        if bytes[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &bytes[i + 1..];
        if rest.starts_with(b"!--") {
            i = find(i + 4, b"-->");
        } else if rest.starts_with(b"![CDATA[") {
            i = find(i + 9, b"]]>");
        } else if rest.starts_with(b"?") || rest.starts_with(b"!") {
            i = find(i + 1, b">");
        } else if rest.starts_with(b"/") {
            depth = depth.saturating_sub(1);
            i = find(i + 1, b">");
        } else {
            // a start tag: to its `>` outside quoted attribute values
            let mut j = i + 1;
            let mut quote = None;
            while j < bytes.len() {
                match (quote, bytes[j]) {
                    (None, b'"' | b'\'') => quote = Some(bytes[j]),
                    (Some(q), c) if c == q => quote = None,
                    (None, b'>') => break,
                    _ => {}
                }
                j += 1;
            }
            if j < bytes.len() && bytes[j - 1] != b'/' {
                depth += 1;
                if depth > max {
                    let line = 1 + bytes[..i].iter().filter(|&&b| b == b'\n').count();
                    return Err((depth, line));
                }
            }
            i = j + 1;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_number_out_of_range_reads_alike_everywhere() {
        assert_eq!(check_number(0.5, Range::Positive, "s"), Ok(()));
        assert_eq!(
            check_number(0.0, Range::Positive, "s"),
            Err("expected a finite number > 0 s, got 0".into())
        );
        assert_eq!(
            check_number(-1.0, Range::NonNegative, ""),
            Err("expected a finite number ≥ 0, got -1".into())
        );
        assert_eq!(
            check_number(f64::NAN, Range::Any, ""),
            Err("expected a finite number, got NaN".into())
        );
    }

    #[test]
    fn numbers_read_short() {
        assert_eq!(num(0.25), "0.25");
        assert_eq!(num(1e300), "1e300");
        assert_eq!(num(1.2e-12), "1.2e-12");
        assert_eq!(num(43.74406), "43.7441");
        assert_eq!(num(f64::INFINITY), "inf");
    }

    #[test]
    fn xml_depth_counts_elements_not_comments_or_empty_tags() {
        let ok = "<?xml version=\"1.0\"?><!-- <a><b><c> --><robot name=\"a>b\"><link/><link><x/></link></robot>";
        assert_eq!(xml_depth(ok, 2), Ok(()));
        assert_eq!(xml_depth(ok, 1), Err((2, 1)));
        let deep = "<a>".repeat(20_000);
        assert_eq!(xml_depth(&deep, XML_DEPTH), Err((XML_DEPTH + 1, 1)));
    }

    #[test]
    fn bounded_reads_refuse_what_is_too_large() {
        let text = "1,2\n3,4\n";
        let mut out = String::new();
        Bounded::new(text.as_bytes(), 100, 10)
            .read_to_string(&mut out)
            .unwrap();
        assert_eq!(out, text);
        let long = "1,".repeat(100);
        assert!(
            Bounded::new(long.as_bytes(), 1000, 10)
                .read_to_string(&mut String::new())
                .is_err()
        );
        assert!(
            Bounded::new(text.as_bytes(), 4, 10)
                .read_to_string(&mut String::new())
                .is_err()
        );
        let error = read(Path::new("/dev/zero"), 1 << 10).unwrap_err();
        assert!(
            error.to_string().contains("larger than 1024 bytes"),
            "{error}"
        );
    }
}
