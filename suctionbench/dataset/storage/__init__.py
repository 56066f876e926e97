"""Dataset storage in the Dex-Net 3.0 tensor layout, readable by the original gqcnn trainer.

Layout of a dataset directory ``DIR``::

    DIR/config.json                                   dataset card (+ the keys gqcnn's TensorDataset reads)
    DIR/tensors/depth_ims_tf_table_XXXXX.npz          float32 (n, 32, 32, 1)  depth thumbnails
    DIR/tensors/context_ims_tf_table_XXXXX.npz        float32 (n, 32, 32, 1)  context thumbnails (3x the view)
    DIR/tensors/hand_poses_XXXXX.npz                  float32 (n, 7)          grasp pose vectors
    DIR/tensors/robust_suction_wrench_resistance_XXXXX.npz  float32 (n,)     robust label in [0, 1]
    DIR/tensors/object_labels_XXXXX.npz               int32 (n,)   index into the card's object list
    DIR/tensors/pose_labels_XXXXX.npz                 int32 (n,)   stable pose id
    DIR/tensors/image_labels_XXXXX.npz                int32 (n,)   global image id
    DIR/tensors/seal_flags_XXXXX.npz                  uint8 (n,)   nominal seal (0/1)
    DIR/tensors/wrench_resistance_XXXXX.npz           uint8 (n,)   nominal wrench resistance (0/1)
    DIR/tensors/shard_XXXXX.json                      shard manifest, written last
    DIR/splits/{image_wise,object_wise}/{train,val}_indices.npz, metadata.json

Every ``.npz`` holds one array under the key ``arr_0``; ``XXXXX`` is the zero-padded shard index
(gqcnn parses exactly five digits); each shard holds ``datapoints_per_shard`` datapoints (Dex-Net:
1000) except the last, which may be partial. Datapoint ``j`` of shard ``i`` has the global index
``i * datapoints_per_shard + j``, the index the split files refer to -- the same arithmetic as
``autolab_core.TensorDataset``, which is why only the last shard may be partial.

Why a manifest per shard
------------------------
A shard is several files, and no file system renames several files at once. Each file is written
under a temporary name and renamed, and the manifest ``shard_XXXXX.json`` -- the sha256 and size
of every file of the shard plus its datapoint count -- is renamed into place last. So a shard is
complete iff its manifest exists and the hashes match: an interrupted or crashed write, a
truncated copy or a flipped bit is found by `DatasetReader.verify` and the shard regenerated,
without trusting file modification times or sizes. gqcnn ignores the ``.json`` files.

Why the ``.npz`` files are written by hand
------------------------------------------
``np.savez_compressed`` stamps each zip entry with the current time, so the same arrays give
different bytes (and hashes) on every run. `_npz_bytes` writes the same zip layout (one deflated
``arr_0.npy`` entry, readable by ``np.load``) with a fixed timestamp: same data, same bytes, same
manifest -- generation is reproducible down to the file hashes.

Submodules: `format` the field tables, names and byte-level file helpers; `writer` `DatasetWriter`;
`reader` `DatasetReader`; `card` the dataset card, the train/val splits and `dexnet_compatible`.
This package re-exports their public names (and the private ones other modules import).
"""

from suctionbench.dataset.storage.card import (
    dexnet_compatible,
    held_out_keys,
    read_card,
    read_split,
    write_card,
    write_splits,
)
from suctionbench.dataset.storage.format import (
    _DATA_RE,
    _MANIFEST_RE,
    CARD_NAME,
    DEFAULT_DATAPOINTS_PER_SHARD,
    FIELDS,
    GQCNN_FIELDS,
    HAND_POSE_COLUMNS,
    LATER_FIELDS,
    MANIFEST_FORMAT,
    MAX_SHARDS,
    NPZ_KEY,
    SPLIT_DIR,
    SPLIT_KINDS,
    SPLIT_PARTS,
    TENSOR_DIR,
    THUMBNAIL_SHAPE,
    FieldSpec,
    _npz_bytes,
    gqcnn_field_config,
    is_field_config,
    manifest_name,
    shard_file_name,
)
from suctionbench.dataset.storage.reader import DatasetReader
from suctionbench.dataset.storage.writer import DatasetWriter

__all__ = [
    "CARD_NAME",
    "DEFAULT_DATAPOINTS_PER_SHARD",
    "FIELDS",
    "GQCNN_FIELDS",
    "HAND_POSE_COLUMNS",
    "LATER_FIELDS",
    "MANIFEST_FORMAT",
    "MAX_SHARDS",
    "NPZ_KEY",
    "SPLIT_DIR",
    "SPLIT_KINDS",
    "SPLIT_PARTS",
    "TENSOR_DIR",
    "THUMBNAIL_SHAPE",
    "_DATA_RE",
    "_MANIFEST_RE",
    "DatasetReader",
    "DatasetWriter",
    "FieldSpec",
    "_npz_bytes",
    "dexnet_compatible",
    "gqcnn_field_config",
    "held_out_keys",
    "is_field_config",
    "manifest_name",
    "read_card",
    "read_split",
    "shard_file_name",
    "write_card",
    "write_splits",
]
