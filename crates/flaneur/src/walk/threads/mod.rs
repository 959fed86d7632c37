//! The threads a walk's loaders run on, shared by every mode that reads off the
//! viewer's thread: the viewer's latest position handed to a loader (`mailbox`), a
//! paced walk's poses played at their times (`pace`), the order loads come in
//! (`load_order`), a batch of meshes' pages asked for together (`mesh_batch`), a
//! prefetch thread's answer taken in time (`receive`), the full meshes read for the
//! objects a walk drew coarse (`refining`), and what loaders could not read, for damage
//! (`damage`) or on the network (`load_failures`), named for the walk's summary.

pub(crate) mod damage;
pub(crate) mod load_failures;
pub(crate) mod load_order;
pub(crate) mod mailbox;
pub(crate) mod mesh_batch;
pub(crate) mod pace;
pub(crate) mod receive;
pub(crate) mod refining;
