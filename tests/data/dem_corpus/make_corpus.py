#!/usr/bin/env python3
"""Regenerates the malformed-DEM corpus (needs numpy + tifffile). The files are committed;
CI only reads them. `expected.txt` pairs each file with the error text it must produce."""
import struct, zlib
import numpy as np
import tifffile

GEO = [
    (33550, 'd', 3, (90.0, 90.0, 0.0), False),
    (33922, 'd', 6, (0, 0, 0, 500000.0, 4000000.0, 0), False),
    (34735, 'H', 16, (1, 1, 0, 3, 1024, 0, 1, 1, 1025, 0, 1, 1, 3072, 0, 1, 32616), False),
]

def tif(name, data, tags=GEO, **kw):
    tifffile.imwrite(name, data, extratags=tags, photometric=kw.pop('photometric', 'minisblack'), **kw)

def patch_tag(name, code, value):
    """Overwrites the (inline, SHORT or LONG) value of tag `code` in the first IFD."""
    b = bytearray(open(name, 'rb').read())
    assert b[:2] == b'II'
    ifd = struct.unpack_from('<I', b, 4)[0]
    n = struct.unpack_from('<H', b, ifd)[0]
    for k in range(n):
        at = ifd + 2 + 12 * k
        tag, typ, cnt = struct.unpack_from('<HHI', b, at)
        if tag == code:
            if typ == 3:
                struct.pack_into('<H', b, at + 8, value)
            else:
                struct.pack_into('<I', b, at + 8, value)
            open(name, 'wb').write(bytes(b))
            return
    raise KeyError(code)

ramp = (np.arange(12 * 10, dtype=np.float32).reshape(10, 12) + 100.0)

src = open('../../../../shared/data/dem/jacksboro_int16.tif', 'rb').read()
open('truncated.tif', 'wb').write(src[:3000])
tif('jpeg2000.tif', ramp)
patch_tag('jpeg2000.tif', 259, 34712)
tif('all_nodata.tif', np.full((10, 12), -9999, np.float32), GEO + [(42113, 's', 0, '-9999', False)])
bad = ramp.copy(); bad[3, 4] = np.inf
tif('infinite.tif', bad)
tif('huge.tif', ramp)
patch_tag('huge.tif', 256, 100000)
patch_tag('huge.tif', 257, 100000)
patch_tag('huge.tif', 278, 100000)
tif('rgb.tif', np.zeros((10, 12, 3), np.uint8), photometric='rgb')
tif('rotated.tif', ramp, [(34264, 'd', 16, (90, 5, 0, 500000, 5, -90, 0, 4000000, 0, 0, 0, 0, 0, 0, 0, 1), False),
                          GEO[2]])
tif('tiepoint_only.tif', ramp, [GEO[1], GEO[2]])
tif('bad_geokeys.tif', ramp, [GEO[0], GEO[1], (34735, 'H', 8, (1, 1, 0, 10, 1024, 0, 1, 1), False)])
tif('bad_nodata.tif', ramp, GEO + [(42113, 's', 0, 'abc', False)])
tif('zero_scale.tif', ramp, [(33550, 'd', 3, (0.0, 90.0, 0.0), False)] + GEO[1:])
tif('latitude.tif', ramp, [(33550, 'd', 3, (0.001, 0.001, 0.0), False),
                           (33922, 'd', 6, (0, 0, 0, 10.0, 120.0, 0), False),
                           (34735, 'H', 12, (1, 1, 0, 2, 1024, 0, 1, 2, 2048, 0, 1, 4326), False)])
tif('one_row.tif', ramp[:1])

HDR = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 10\nNODATA_value -9999\n"
open('nan.asc', 'w').write(HDR + "1 2 3\n4 nan 6\n")
open('short.asc', 'w').write(HDR + "1 2 3\n4 5\n")
open('long.asc', 'w').write(HDR + "1 2 3\n4 5 6 7\n")
open('huge.asc', 'w').write("ncols 1000000\nnrows 1000000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n")
open('no_cellsize.asc', 'w').write("ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\n1 2 3\n4 5 6\n")
open('bad_header.asc', 'w').write("ncols abc\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n")
open('all_nodata.asc', 'w').write(HDR + "-9999 -9999 -9999\n-9999 -9999 -9999\n")
open('binary.asc', 'wb').write(HDR.encode() + b"1 2 \xff\xfe 3\n")
open('one_row.asc', 'w').write("ncols 3\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n")
open('fractional.asc', 'w').write("ncols 2.5\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n4 5 6\n")

def png(name, arr, mode):
    """A minimal PNG writer (greyscale 16-bit or RGB 8-bit)."""
    h, w = arr.shape[:2]
    ct, depth = (0, 16) if mode == 'L16' else (2, 8)
    raw = b''.join(b'\0' + (arr[r].astype('>u2').tobytes() if mode == 'L16' else arr[r].tobytes()) for r in range(h))
    def chunk(t, d):
        return struct.pack('>I', len(d)) + t + d + struct.pack('>I', zlib.crc32(t + d) & 0xffffffff)
    data = b'\x89PNG\r\n\x1a\n' + chunk(b'IHDR', struct.pack('>IIBBBBB', w, h, depth, ct, 0, 0, 0)) \
        + chunk(b'IDAT', zlib.compress(raw)) + chunk(b'IEND', b'')
    open(name, 'wb').write(data)
    return data

g16 = (np.arange(12 * 10).reshape(10, 12) * 500).astype(np.uint16)
png('rgb.png', np.zeros((10, 12, 3), np.uint8), 'RGB')
open('rgb.json', 'w').write('{"png_u16_maps": {"0": 0, "65535": 100}}')
png('no_sidecar.png', g16, 'L16')
png('lying.png', g16, 'L16')
open('lying.json', 'w').write('{"rows": 344, "cols": 403, "png_u16_maps": {"0": 0, "65535": 100}}')
full = png('truncated.png', g16, 'L16')
open('truncated.png', 'wb').write(full[:60])
open('truncated.json', 'w').write('{"png_u16_maps": {"0": 0, "65535": 100}}')
png('samemap.png', g16, 'L16')
open('samemap.json', 'w').write('{"png_u16_maps": {"5": 1.0, "5.0": 2.0}}')
png('badjson.png', g16, 'L16')
open('badjson.json', 'w').write('{"png_u16_maps": {"0": 0, "65535": 100}')
png('allvoid.png', np.zeros((10, 12), np.uint16), 'L16')
open('allvoid.json', 'w').write('{"png_u16_maps": {"1": 0, "65535": 100}, "nodata_raw": 0}')

open('N10E010.hgt', 'wb').write(b'\0' * 1000)
open('tile.hgt', 'wb').write(b'\0' * 1000)
