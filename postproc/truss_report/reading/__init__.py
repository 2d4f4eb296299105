"""The reading layer: typed readers of the HDF5 files truss-sim and truss-campaign write. Each
reader checks the layout it needs and raises InputError naming the file and what is wrong; it
returns dataclasses (a design sweep's per-value table: a pandas DataFrame). Nothing here judges or
formats: this layer imports numpy, h5py and pandas only."""
