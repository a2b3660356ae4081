//! The mutations of the stable fuzz tests (tests/fuzz_*.rs).

/// SplitMix64: small, fast and good enough to pick mutations.
pub struct Mutator {
    pub state: u64,
}

impl Mutator {
    pub fn next(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    pub fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// A range of at most `longest` bytes inside `len`.
    pub fn range(&mut self, len: usize, longest: usize) -> std::ops::Range<usize> {
        let start = self.below(len + 1);
        let end = (start + self.below(longest + 1)).min(len);
        start..end
    }

    /// One of `corpus` with one to four mutations: byte flips, deletions, duplications,
    /// insertions of `tokens`, numbers replaced by tokens, splices from another input,
    /// truncations and swapped lines.
    pub fn mutate(&mut self, corpus: &[Vec<u8>], tokens: &[&str]) -> Vec<u8> {
        let mut bytes = corpus[self.below(corpus.len())].clone();
        for _ in 0..1 + self.below(4) {
            let len = bytes.len();
            match self.below(9) {
                0 if len > 0 => {
                    let i = self.below(len);
                    bytes[i] = self.next() as u8;
                }
                1 => {
                    let r = self.range(len, 16);
                    bytes.drain(r);
                }
                2 => {
                    let r = self.range(len, 64);
                    let copy = bytes[r].to_vec();
                    let at = self.below(len + 1);
                    bytes.splice(at..at, copy);
                }
                3 | 4 => {
                    let token = tokens[self.below(tokens.len())].as_bytes();
                    let at = self.below(len + 1);
                    bytes.splice(at..at, token.iter().copied());
                }
                5 => {
                    // A number replaced by a token: find a digit near a random place.
                    let at = self.below(len + 1);
                    if let Some(offset) = bytes[at..].iter().position(u8::is_ascii_digit) {
                        let start = at + offset;
                        let end = start
                            + bytes[start..]
                                .iter()
                                .position(|b| !(b.is_ascii_digit() || *b == b'.'))
                                .unwrap_or(bytes.len() - start);
                        let token = tokens[self.below(tokens.len())].as_bytes();
                        bytes.splice(start..end, token.iter().copied());
                    }
                }
                6 => {
                    let other = &corpus[self.below(corpus.len())];
                    let r = self.range(other.len(), 200);
                    let at = self.below(len + 1);
                    bytes.splice(at..at, other[r].iter().copied());
                }
                7 => {
                    let at = self.below(len + 1);
                    bytes.truncate(at);
                }
                _ => {
                    // Two lines swapped.
                    let text = String::from_utf8_lossy(&bytes).into_owned();
                    let mut lines: Vec<&str> = text.lines().collect();
                    if lines.len() > 1 {
                        let (a, b) = (self.below(lines.len()), self.below(lines.len()));
                        lines.swap(a, b);
                        bytes = lines.join("\n").into_bytes();
                    }
                }
            }
        }
        bytes
    }
}

/// How many executions and which seed a fuzz test runs: `RT_GPU_FUZZ_EXECUTIONS` (default
/// `default_executions`) and `RT_GPU_FUZZ_SEED` (default 1).
pub fn run_settings(default_executions: usize) -> (usize, u64) {
    let var = |name: &str| std::env::var(name).ok().and_then(|v| v.parse::<u64>().ok());
    let executions = var("RT_GPU_FUZZ_EXECUTIONS").map_or(default_executions, |n| n as usize);
    (executions, var("RT_GPU_FUZZ_SEED").unwrap_or(1))
}

/// Runs `check`, a panic included: `None` if it held, else what went wrong.
pub fn problem(check: impl FnOnce() -> Result<(), String>) -> Option<String> {
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(check)) {
        Ok(Ok(())) => None,
        Ok(Err(problem)) => Some(problem),
        Err(panic) => Some(format!(
            "panic: {}",
            panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
                .unwrap_or_default()
        )),
    }
}
