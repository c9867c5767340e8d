"""Recordings and their files (CSV, Parquet, NPZ)."""

from .io import load, save, write_csv_mixed, write_table
from .recording import Gap, Metadata, Recording, SamplingReport, default_temperature_names

__all__ = ["Gap", "Metadata", "Recording", "SamplingReport", "default_temperature_names",
           "load", "save", "write_csv_mixed", "write_table"]
