//! One VIEW at a time over a session's connection (Zheng Fig. 5.3b: no request until
//! the last was answered), as both kinds of client send them: the frame sent and not
//! yet answered, and the lowest frame the next VIEW may have.

use std::net::TcpStream;

use crate::error::StreamError;
use crate::protocol::{receive, send, Message, ViewPacket, MAX_TO_CLIENT};

#[derive(Debug)]
pub(crate) struct Exchange {
    pub(crate) stream: TcpStream,
    /// The frame of the VIEW sent and not yet answered.
    pending: Option<u32>,
    /// One past the last frame sent.
    next_frame: u32,
}

impl Exchange {
    pub(crate) fn new(stream: TcpStream) -> Exchange {
        Exchange {
            stream,
            pending: None,
            next_frame: 0,
        }
    }

    /// The lowest frame the next VIEW may have.
    pub(crate) fn next_frame(&self) -> u32 {
        self.next_frame
    }

    /// Goes on over `stream`, a view sent on the old connection forgotten.
    pub(crate) fn resume_on(&mut self, stream: TcpStream) {
        self.stream = stream;
        self.pending = None;
    }

    pub(crate) fn send_view(&mut self, view: &ViewPacket) -> Result<(), StreamError> {
        if let Some(frame) = self.pending {
            return Err(StreamError::Malformed(format!(
                "frame {frame}'s answer has not come yet"
            )));
        }
        send(&mut self.stream, &Message::View(*view))?;
        self.pending = Some(view.frame);
        self.next_frame = self.next_frame.max(view.frame.saturating_add(1));
        Ok(())
    }

    /// Waits for the pending view's answer, `frame_of` reading an answer's frame
    /// (`None` for a message that is not one): the message and its bytes on the wire.
    pub(crate) fn answer(
        &mut self,
        frame_of: impl Fn(&Message) -> Option<u32>,
    ) -> Result<(Message, usize), StreamError> {
        let asked = self
            .pending
            .ok_or_else(|| StreamError::Malformed("no view is waiting for an answer".into()))?;
        let (m, bytes) = match receive(&mut self.stream, MAX_TO_CLIENT)? {
            Some((Message::Refused(why), _)) => return Err(StreamError::Refused(why)),
            Some(got) => got,
            None => return Err(StreamError::Refused("closed mid-session".into())),
        };
        match frame_of(&m) {
            None => Err(StreamError::Malformed(format!(
                "a {m:?} where frame {asked}'s answer was due"
            ))),
            Some(frame) if frame != asked => Err(StreamError::Malformed(format!(
                "the answer to frame {frame} where frame {asked}'s was due"
            ))),
            Some(_) => {
                self.pending = None;
                Ok((m, bytes))
            }
        }
    }
}
