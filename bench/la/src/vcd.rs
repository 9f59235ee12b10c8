//! Streaming VCD reader for sigrok-cli's `-O vcd` output and the virtual bench's VCDs.
//!
//! Reads token by token in constant memory: header (`$timescale` of any number and unit such
//! as `1 ns`, `100 ps` or `41667 ps`, `$scope`/`$var` declarations, `$comment`s, sigrok's
//! "Acquisition with 4/8 channels at 24 MHz" comment for the sample rate), then value changes:
//! `#time`, scalar `0!`/`1!` and vector `b0101 !` (one channel per bit, `name[i]`), several per
//! line or one per line, `$dumpvars` blocks. `x`/`z` carry no level and are skipped; real and
//! string values are ignored. Times must not go backwards. sigrok-cli's `META samplerate: N`
//! line (written when it converts a file) may precede the header.

use std::collections::HashMap;
use std::io::BufRead;

use anyhow::{anyhow, bail, Context, Result};

use super::levels::{CaptureInfo, Format, Sink};

/// Whitespace-separated tokens of a stream, with the line number for messages.
struct Tokens<R> {
    reader: R,
    line: usize,
}

impl<R: BufRead> Tokens<R> {
    // read the next token into `out`; false at end of input
    fn next(&mut self, out: &mut Vec<u8>) -> Result<bool> {
        out.clear();
        loop {
            let buf = self.reader.fill_buf().context("reading VCD")?;
            if buf.is_empty() {
                return Ok(!out.is_empty());
            }
            let mut i = 0;
            if out.is_empty() {
                while i < buf.len() && buf[i].is_ascii_whitespace() {
                    self.line += usize::from(buf[i] == b'\n');
                    i += 1;
                }
            }
            let start = i;
            while i < buf.len() && !buf[i].is_ascii_whitespace() {
                i += 1;
            }
            out.extend_from_slice(&buf[start..i]);
            let ended = i < buf.len();
            self.reader.consume(i);
            if ended && !out.is_empty() {
                return Ok(true);
            }
        }
    }

    // read tokens up to `$end` and return them joined by spaces
    fn until_end(&mut self, scratch: &mut Vec<u8>) -> Result<String> {
        let mut text = String::new();
        loop {
            if !self.next(scratch)? {
                bail!("line {}: missing $end", self.line + 1);
            }
            if scratch.as_slice() == b"$end" {
                return Ok(text);
            }
            if !text.is_empty() {
                text.push(' ');
            }
            text.push_str(&String::from_utf8_lossy(scratch));
        }
    }
}

/// A declared variable: `width` channels starting at `first`.
#[derive(Clone, Copy)]
struct Var {
    first: usize,
    width: usize,
}

/// VCD reader, positioned after `$enddefinitions`.
pub struct VcdReader<R> {
    tokens: Tokens<R>,
    info: CaptureInfo,
    /// Time unit in femtoseconds.
    unit_fs: u128,
    short_ids: Vec<Option<Var>>,
    long_ids: HashMap<Vec<u8>, Var>,
}

impl<R: BufRead> VcdReader<R> {
    // parse the header
    pub fn new(reader: R) -> Result<Self> {
        let mut me = Self {
            tokens: Tokens { reader, line: 0 },
            info: CaptureInfo {
                format: Format::Vcd,
                channels: Vec::new(),
                sample_rate_hz: None,
            },
            unit_fs: 1_000_000,
            short_ids: vec![None; 128],
            long_ids: HashMap::new(),
        };
        let mut token = Vec::new();
        loop {
            if !me.tokens.next(&mut token)? {
                bail!("not a VCD file: no $enddefinitions");
            }
            match token.as_slice() {
                b"$enddefinitions" => {
                    me.tokens.until_end(&mut token)?;
                    break;
                }
                b"$timescale" => me.unit_fs = parse_timescale(&me.tokens.until_end(&mut token)?)?,
                b"$var" => {
                    let decl = me.tokens.until_end(&mut token)?;
                    me.declare(&decl)
                        .with_context(|| format!("line {}: $var {decl}", me.tokens.line + 1))?;
                }
                // sigrok-cli puts "META samplerate: N" first when converting a file.
                b"META" => {
                    let key = me.tokens.next(&mut token).map(|_| token.clone())?;
                    me.tokens.next(&mut token)?;
                    if key == b"samplerate:" {
                        me.info.sample_rate_hz = std::str::from_utf8(&token)
                            .ok()
                            .and_then(|v| v.parse().ok());
                    }
                }
                b"$comment" => {
                    let text = me.tokens.until_end(&mut token)?;
                    me.info.sample_rate_hz =
                        me.info.sample_rate_hz.or_else(|| sigrok_sample_rate(&text));
                }
                t if t.starts_with(b"$") => {
                    me.tokens.until_end(&mut token)?;
                }
                t => bail!(
                    "line {}: unexpected {:?} in VCD header",
                    me.tokens.line + 1,
                    String::from_utf8_lossy(t)
                ),
            }
        }
        if me.info.channels.is_empty() {
            bail!("VCD declares no signals");
        }
        Ok(me)
    }

    // channel names and sample rate from the header
    pub fn info(&self) -> &CaptureInfo {
        &self.info
    }

    // add the channels of one `$var type width id name [range]` declaration
    fn declare(&mut self, decl: &str) -> Result<()> {
        let fields: Vec<&str> = decl.split_whitespace().collect();
        let [_kind, width, id, name, rest @ ..] = fields.as_slice() else {
            bail!("too few fields")
        };
        let width: usize = width.parse().map_err(|_| anyhow!("bad width {width:?}"))?;
        if width == 0 {
            bail!("zero width");
        }
        let var = Var {
            first: self.info.channels.len(),
            width,
        };
        let range = rest.first().filter(|r| r.starts_with('['));
        if width == 1 {
            self.info
                .channels
                .push(format!("{name}{}", range.copied().unwrap_or("")));
        } else {
            let (base, lsb, ascending) = bit_names(name, range.copied());
            for bit in 0..width {
                let index = if ascending {
                    lsb + bit
                } else {
                    lsb.saturating_sub(bit)
                };
                self.info.channels.push(format!("{base}[{index}]"));
            }
        }
        let id = id.as_bytes();
        match id {
            [b] if (*b as usize) < self.short_ids.len() => {
                self.short_ids[*b as usize].get_or_insert(var);
            }
            _ => {
                self.long_ids.entry(id.to_vec()).or_insert(var);
            }
        }
        Ok(())
    }

    // variable of an identifier code
    fn lookup(&self, id: &[u8]) -> Result<Var> {
        let var = match id {
            [b] if (*b as usize) < self.short_ids.len() => self.short_ids[*b as usize],
            _ => self.long_ids.get(id).copied(),
        };
        var.ok_or_else(|| {
            anyhow!(
                "line {}: unknown identifier code {:?}",
                self.tokens.line + 1,
                String::from_utf8_lossy(id)
            )
        })
    }

    // stream every value change into `sink`; returns the last time in ps
    pub fn stream(&mut self, sink: &mut impl Sink) -> Result<u64> {
        let (mut token, mut id) = (Vec::new(), Vec::new());
        let mut now: Option<u64> = None;
        while self.tokens.next(&mut token)? {
            let line = self.tokens.line + 1;
            let time = now.unwrap_or(0);
            match token[0] {
                b'#' => {
                    let raw: u64 = std::str::from_utf8(&token[1..])
                        .ok()
                        .and_then(|s| s.parse().ok())
                        .ok_or_else(|| {
                            anyhow!(
                                "line {line}: bad time {:?}",
                                String::from_utf8_lossy(&token)
                            )
                        })?;
                    let ps = u64::try_from((raw as u128 * self.unit_fs + 500) / 1000)
                        .map_err(|_| anyhow!("line {line}: time {raw} overflows"))?;
                    if now.is_some_and(|n| ps < n) {
                        bail!("line {line}: time goes backwards (#{raw})");
                    }
                    now = Some(ps);
                    sink.advance(ps);
                }
                b'0' | b'1' => {
                    let var = self.lookup(&token[1..])?;
                    if var.width != 1 {
                        bail!("line {line}: scalar value for a {}-bit signal", var.width);
                    }
                    sink.level(time, var.first, token[0] == b'1');
                }
                b'x' | b'X' | b'z' | b'Z' => {
                    self.lookup(&token[1..])?;
                }
                b'b' | b'B' => {
                    if !self.tokens.next(&mut id)? {
                        bail!("line {line}: vector value without identifier");
                    }
                    let var = self.lookup(&id)?;
                    apply_bits(&token[1..], var, time, sink)
                        .with_context(|| format!("line {line}"))?;
                }
                b'r' | b'R' | b's' | b'S' => {
                    self.tokens.next(&mut id)?;
                }
                b'$' => match token.as_slice() {
                    b"$dumpvars" | b"$dumpall" | b"$dumpon" | b"$dumpoff" | b"$end" => {}
                    _ => {
                        self.tokens.until_end(&mut id)?;
                    }
                },
                _ => bail!(
                    "line {line}: unexpected {:?}",
                    String::from_utf8_lossy(&token)
                ),
            }
        }
        Ok(now.unwrap_or(0))
    }
}

// report the bits of a vector value, least significant last in the text
fn apply_bits(bits: &[u8], var: Var, time_ps: u64, sink: &mut impl Sink) -> Result<()> {
    if bits.is_empty() || bits.len() > var.width {
        bail!(
            "vector value of {} bits for a {}-bit signal",
            bits.len(),
            var.width
        );
    }
    // Shorter values are left-extended with 0, or with x/z when they start with x/z.
    let pad = if bits[0] == b'1' { b'0' } else { bits[0] };
    for bit in 0..var.width {
        let c = if bit < bits.len() {
            bits[bits.len() - 1 - bit]
        } else {
            pad
        };
        match c {
            b'0' | b'1' => sink.level(time_ps, var.first + bit, c == b'1'),
            b'x' | b'X' | b'z' | b'Z' => {}
            _ => bail!("bad bit {:?}", c as char),
        }
    }
    Ok(())
}

// base name, lowest index and direction of a vector's bits from `name [7:0]` or `name[7:0]`
fn bit_names<'a>(name: &'a str, range: Option<&'a str>) -> (&'a str, usize, bool) {
    let (base, range) = match (range, name.find('[')) {
        (Some(r), _) => (name, r),
        (None, Some(i)) => (&name[..i], &name[i..]),
        (None, None) => return (name, 0, true),
    };
    let bounds: Vec<usize> = range
        .trim_matches(['[', ']'])
        .split(':')
        .filter_map(|s| s.parse().ok())
        .collect();
    match bounds.as_slice() {
        // `[7:0]`: bit 0 is index 0; `[0:7]`: bit 0 is index 7.
        [msb, lsb] => (base, *lsb, msb >= lsb),
        _ => (base, 0, true),
    }
}

// femtoseconds per time unit from "1 ns", "100ps", "41667 ps"
pub fn parse_timescale(text: &str) -> Result<u128> {
    let text: String = text.split_whitespace().collect();
    let digits = text.chars().take_while(char::is_ascii_digit).count();
    let number: u128 = text[..digits]
        .parse()
        .map_err(|_| anyhow!("bad $timescale {text:?}"))?;
    let unit: u128 = match &text[digits..] {
        "s" => 1_000_000_000_000_000,
        "ms" => 1_000_000_000_000,
        "us" => 1_000_000_000,
        "ns" => 1_000_000,
        "ps" => 1_000,
        "fs" => 1,
        other => bail!("bad $timescale unit {other:?}"),
    };
    Ok(number * unit)
}

// sample rate from sigrok's "Acquisition with 4/8 channels at 24 MHz" comment
fn sigrok_sample_rate(comment: &str) -> Option<f64> {
    let rest = &comment[comment.find(" at ")? + 4..];
    // Here the unit is required ("at 24 MHz"); the CSV header's parser defaults it to Hz.
    rest.split_whitespace().nth(1)?;
    super::csv::parse_rate(rest)
}
