"""``modd dataset``: the on-board archive (MCAP) as a dataset scientists open
in their own tools: CF-1.11 trajectory NetCDF with ACDD-1.3 attributes,
Parquet, CSV, GeoJSON and GPX, every sample with its time, its UDUNITS unit,
its CF standard name where the model declares one, and the platform's
position interpolated to it (docs/user-guide/datasets.md); with
``--received``, the windows the subscribers received (the base-station record).

Modules: ``record`` (the archive record contract, decoded), ``mcapread``
(an archive streamed chunk by chunk), ``position`` (the track and its
interpolation), ``plan`` (what to export, from the model), ``export`` (the
two passes), ``resample`` (the wide form), one writer per format
(``netcdf``, ``tables``, ``tracks``), ``received`` (the base-station record's
windows: plan and reader), ``cli``.
"""
