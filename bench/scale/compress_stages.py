# Label-only stage series from one segmented 1220^3 scan, for timing `track` at full size:
# stage s compresses the specimen along z by the study's strain (slice k' <- slice round(k'/(1-e))),
# platen at the top; the top e*nz slices become void. Grains flatten (not physical): a cost test only.
import h5py, numpy as np, sys
src = h5py.File(sys.argv[1])['labels']
vs = h5py.File(sys.argv[1])['labels'].attrs['voxel_size_m']
nz = src.shape[0]
lab = np.empty(src.shape, np.uint32)
for k in range(0, nz, 16): src.read_direct(lab, np.s_[k:k+16], np.s_[k:k+16])
for s, e in enumerate([0.0, 0.044, 0.0712, 0.1128, 0.1548]):
    with h5py.File(f'{sys.argv[2]}/L{s}.h5', 'w') as f:
        d = f.create_dataset('labels', shape=lab.shape, dtype=np.uint32, chunks=(16, 256, 256), compression='gzip', compression_opts=1, shuffle=True)
        d.attrs['voxel_size_m'] = vs; d.attrs['origin_m'] = np.zeros(3)
        f.attrs['voxel_size_m'] = vs; f.attrs['origin_m'] = np.zeros(3)
        for k0 in range(0, nz, 16):
            k = np.arange(k0, min(nz, k0 + 16))
            old = np.rint(k / (1 - e)).astype(np.int64)
            blk = np.zeros((len(k),) + lab.shape[1:], np.uint32)
            ok = old < nz
            blk[ok] = lab[old[ok]]
            d[k0:k0 + len(k)] = blk
    print('stage', s, flush=True)
