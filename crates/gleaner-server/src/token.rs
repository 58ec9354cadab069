//! The bearer token that guards every write: read from an environment variable or a file,
//! compared in constant time, never printed by `Debug` and never logged.

use std::fmt;
use std::path::Path;

use subtle::ConstantTimeEq;

/// Shortest token accepted, bytes: guessing one is out of reach over a network.
pub const MIN_TOKEN_LEN: usize = 16;

/// A write token. `Debug` shows `Token(****)`; the only way to read it back is
/// [`Token::reveal`], for the one line that hands it to the operator.
#[derive(Clone)]
pub struct Token(Vec<u8>);

impl fmt::Debug for Token {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("Token(****)")
    }
}

/// Why a token was refused.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TokenError {
    /// Shorter than [`MIN_TOKEN_LEN`] (the length, never the token, is reported).
    #[error("the token has {0} characters: at least {MIN_TOKEN_LEN} are needed")]
    TooShort(usize),
    /// Contains whitespace or control characters, which an HTTP header cannot carry.
    #[error("the token contains whitespace or control characters")]
    BadCharacters,
    /// The token file could not be read.
    #[error("{path}: cannot read the token file: {reason}")]
    File {
        /// The file.
        path: String,
        /// The OS message.
        reason: String,
    },
    /// The system's random source failed.
    #[error("cannot draw a random token: {0}")]
    Random(String),
}

impl Token {
    /// A token from its text (surrounding whitespace removed).
    pub fn new(text: &str) -> Result<Self, TokenError> {
        let t = text.trim();
        if t.len() < MIN_TOKEN_LEN {
            return Err(TokenError::TooShort(t.len()));
        }
        if t.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(TokenError::BadCharacters);
        }
        Ok(Self(t.as_bytes().to_vec()))
    }

    /// The token stored in `path` (its first line; a trailing newline is ignored).
    pub fn from_file(path: &Path) -> Result<Self, TokenError> {
        let text = std::fs::read_to_string(path).map_err(|e| TokenError::File {
            path: path.display().to_string(),
            reason: e.to_string(),
        })?;
        Self::new(text.lines().next().unwrap_or(""))
    }

    /// 32 random bytes from the operating system, as 64 hex digits.
    pub fn random() -> Result<Self, TokenError> {
        let mut bytes = [0u8; 32];
        getrandom::fill(&mut bytes).map_err(|e| TokenError::Random(e.to_string()))?;
        let hex: String = bytes.iter().map(|b| format!("{b:02x}")).collect();
        Self::new(&hex)
    }

    /// The token's text, for handing it to the operator once (never for logs).
    pub fn reveal(&self) -> &str {
        std::str::from_utf8(&self.0).unwrap_or("")
    }

    /// Whether `candidate` is this token, in time independent of where they differ.
    pub fn matches(&self, candidate: &[u8]) -> bool {
        // Lengths are compared in constant time too, as a choice (a length leak alone would
        // not reveal a random token, but there is no reason to give it).
        let len_ok = (self.0.len() as u64).ct_eq(&(candidate.len() as u64));
        let n = self.0.len().min(candidate.len());
        let bytes_ok = self.0[..n].ct_eq(&candidate[..n]);
        (len_ok & bytes_ok).into()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_match_only_themselves_and_never_print() {
        let t = Token::new("0123456789abcdef-token").unwrap();
        assert!(t.matches(b"0123456789abcdef-token"));
        assert!(!t.matches(b"0123456789abcdef-tokem"));
        assert!(!t.matches(b"0123456789abcdef-toke"));
        assert!(!t.matches(b"0123456789abcdef-token2"));
        assert!(!t.matches(b""));
        assert_eq!(format!("{t:?}"), "Token(****)");
        assert!(matches!(Token::new("short"), Err(TokenError::TooShort(5))));
        assert!(matches!(
            Token::new("0123456789 abcdef"),
            Err(TokenError::BadCharacters)
        ));
        let r = Token::random().unwrap();
        assert_eq!(r.reveal().len(), 64);
        assert_ne!(r.reveal(), Token::random().unwrap().reveal());
    }
}
