"""Why a batch cannot start; each message is for the user, and nothing in the folder changed."""

from __future__ import annotations


class DatasetError(ValueError):
    """Scenes that cannot form one dataset (e.g. different levels, duplicate names)."""


class BatchRefusedError(Exception):
    """The batch cannot start (folder locked, other config, unreachable cluster).

    Nothing in the dataset folder has been changed when this is raised.
    """


class DatasetLockedError(BatchRefusedError):
    """Another seahaze process holds the dataset folder's lock."""


class ConfigChangedError(BatchRefusedError):
    """The folder holds a dataset made with another configuration (and ``force`` is off)."""


class ForeignFolderError(BatchRefusedError):
    """The output folder is not seahaze's (a file, another program's files or manifest)."""


class DamagedManifestError(BatchRefusedError):
    """The folder's own ``dataset.json`` is damaged (and ``force`` is off)."""
