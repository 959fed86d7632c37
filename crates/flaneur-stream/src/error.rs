//! What can go wrong in a stream session, on either side.

/// A stream session's failure.
#[derive(Debug, thiserror::Error)]
pub enum StreamError {
    /// The connection failed or closed.
    #[error("stream connection: {0}")]
    Io(#[from] std::io::Error),
    /// The peer sent bytes that are not a message of this protocol, or one out of place.
    #[error("stream protocol: {0}")]
    Malformed(String),
    /// The server refused the session or closed it, saying why.
    #[error("the stream server closed the session: {0}")]
    Refused(String),
    /// The peer stopped reading: what was sent to it filled the connection and stayed
    /// unread past the timeout.
    #[error("the peer stopped reading")]
    Stalled,
    /// The engine refused what the session asked of it (a view, a mesh update).
    #[error(transparent)]
    Engine(#[from] flaneur::Error),
}
