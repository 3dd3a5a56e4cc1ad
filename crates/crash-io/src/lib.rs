//! crash-io: what a crash run writes. ParaView series (.vtu per frame + .pvd), CSV
//! histories (energy, contacts), summary.json, PNG pictures and plots made in process,
//! and exact binary checkpoints. docs/output.md describes every file.

pub mod atomic;
pub mod block_cache;
pub mod checkpoint;
pub mod error;
pub mod frame;
pub mod frame_writer;
pub mod history;
pub mod matsum_read;
pub mod part_frame;
pub mod render;
pub mod results;
pub mod run;
pub mod series;
pub mod summary;
pub mod vtu;
pub mod vtu_encode;
pub mod vtu_read;

pub use checkpoint::{
    decode_checkpoint, read_checkpoint, read_checkpoint_keyed, write_checkpoint,
    write_checkpoint_keyed, CheckpointKey,
};
pub use error::IoError;
pub use frame::{Frame, FrameBody, PartCells, Placement};
pub use frame_writer::BackgroundSeries;
pub use history::{
    read_contacts_csv, read_energy_csv, ContactHistory, ContactRow, EnergyHistory, EnergyRow,
    CONTACTS_CSV, ENERGY_CSV,
};
pub use part_frame::{FrameFromParts, PartFrame};
pub use render::{
    contact_sheet, energy_plot, loglog_plot, render_frame, Camera, Colouring, Image, LogSeries,
    RenderOptions, View,
};
pub use results::{
    csv_name, ResultFile, NODOUT_CSV, NODOUT_HEADER, RCFORC_CSV, RCFORC_HEADER, SPCFORC_CSV,
    SPCFORC_HEADER,
};
pub use run::render_run;
pub use series::{read_pvd, PvdEntry, SeriesWriter, PVD_FILE};
pub use summary::{
    hash_hex, read_summary, write_summary, ClusterSummary, GroupSummary, Indicators, Summary,
    Warning, WarningKind, SUMMARY_JSON,
};
pub use vtu::{Precision, VtuFormat};
pub use vtu_read::read_vtu;
