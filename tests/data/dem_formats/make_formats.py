#!/usr/bin/env python3
"""Regenerates the GeoTIFF encoding fixtures (needs numpy + tifffile, imagecodecs for LZW).
Every file holds z[row, col] = 100 + 3·row − 2·col (+ 0.25 for floats) over 37 × 29 pixels,
row 0 in the north, georeferenced at UTM 16N (500000, 4000000) top-left, 10 m pixels."""
import numpy as np
import tifffile

H, W = 29, 37
r, c = np.mgrid[0:H, 0:W]
base = 100 + 3 * r - 2 * c
SCALE = (33550, 'd', 3, (10.0, 10.0, 0.0), False)
TIE = (33922, 'd', 6, (0, 0, 0, 500000.0, 4000000.0, 0), False)
def keys(raster=1):
    return (34735, 'H', 16, (1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, raster, 3072, 0, 1, 32616), False)
GEO = [SCALE, TIE, keys()]

def w(name, data, tags=GEO, **kw):
    tifffile.imwrite(name, data, extratags=tags, photometric='minisblack', **kw)

w('tiled_i16_deflate_pred2.tif', base.astype(np.int16), tile=(16, 16), compression='deflate', predictor=2)
w('tiled_f32_lzw_pred3.tif', (base + 0.25).astype(np.float32), tile=(16, 16), compression='lzw', predictor=3)
w('strips_u16_packbits.tif', base.astype(np.uint16), rowsperstrip=4, compression='packbits')
w('strips_i32_none.tif', base.astype(np.int32), rowsperstrip=7)
w('strips_u8_lzw_pred2.tif', base.astype(np.uint8), compression='lzw', predictor=2)
w('strips_i8_deflate.tif', (base - 100).astype(np.int8), compression='deflate')
w('strips_f64_deflate_pred3.tif', (base + 0.25).astype(np.float64), compression='deflate', predictor=3)
w('strips_f16_none.tif', (base + 0.25).astype(np.float16))
# PixelIsPoint: the tiepoint is the centre of the north-west pixel
w('point_u16.tif', base.astype(np.uint16), [SCALE, (33922, 'd', 6, (0, 0, 0, 500005.0, 3999995.0, 0), False), keys(2)])
# ModelTransformation instead of scale + tiepoint
w('matrix_i16.tif', base.astype(np.int16),
  [(34264, 'd', 16, (10, 0, 0, 500000, 0, -10, 0, 4000000, 0, 0, 0, 0, 0, 0, 0, 1), False), keys()])
# south-up: row 0 is the south, the y scale is positive in the matrix
w('southup_i16.tif', base[::-1].astype(np.int16),
  [(34264, 'd', 16, (10, 0, 0, 500000, 0, 10, 0, 4000000 - 10 * H, 0, 0, 0, 0, 0, 0, 0, 1), False), keys()])
