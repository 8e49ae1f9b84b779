#!/usr/bin/env python3
"""Writes the SII image that eeprom-blob.xml carries in <Eeprom><Data> (ETG.1000.6 section 5.4, ETG.2010):
the fixed header with the CRC-8 of words 0-6 in word 7, then the Strings, General, FMMU, SyncM and TxPDO
categories of the EXD1002 (2 digital inputs, no mailbox). Run it to regenerate the hex text:
    python3 esi/examples/make-eeprom-blob.py
"""
import struct

VENDOR, PRODUCT, REVISION = 0x00000A5E, 0x03EA3052, 0x00100000
SIZE = 512  # bytes: 4 KiBit


def crc8(data):
    crc = 0xFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = ((crc << 1) ^ 0x07) & 0xFF if crc & 0x80 else (crc << 1) & 0xFF
    return crc


def category(code, data):
    if len(data) % 2:
        data += b'\x00'
    return struct.pack('<HH', code, len(data) // 2) + data


strings = ['EXD1002', 'EXD1002 2Ch. Dig. Input 24V, 3ms (EEPROM image)', 'DigIn', 'Input', 'Channel 1', 'Channel 2']
header = bytearray(128)
struct.pack_into('<BBHHH', header, 0, 0x04, 0x01, 0x0000, 0x0000, 0x0000)  # digital I/O PDI, device emulation
header[14] = crc8(header[0:14])
struct.pack_into('<IIII', header, 16, VENDOR, PRODUCT, REVISION, 0)
struct.pack_into('<H', header, 0x1C * 2, 0)  # no mailbox protocol
struct.pack_into('<HH', header, 0x3E * 2, SIZE // 128 - 1, 1)  # EEPROM size (KiBit - 1), version 1

cats = category(10, bytes([len(strings)]) + b''.join(bytes([len(s)]) + s.encode('ascii') for s in strings))
general = bytearray(32)
general[0], general[1], general[2], general[3] = 3, 0, 1, 2  # group, image, order, name string indices
struct.pack_into('<h', general, 12, 90)  # mA from the E-bus
general[14] = 3
struct.pack_into('<H', general, 16, 0x0011)  # ports 0 and 1: MII
cats += category(30, bytes(general))
cats += category(40, bytes([0x02]))  # FMMU 0: inputs
cats += category(41, struct.pack('<HHBBBB', 0x1000, 1, 0x00, 0x00, 0x01, 4))  # SM0: inputs, 3-buffer, read
txpdo = b''
for ch in range(2):
    # PDO header: index, entries, SM, DC sync, name, flags (fixed content, assigned by default)
    txpdo += struct.pack('<HBBBBH', 0x1A00 + ch, 1, 0, 0, 5 + ch, 0x0012)
    # entry: index, subindex, name, data type (BOOLEAN), bit length, flags
    txpdo += struct.pack('<HBBBBH', 0x6000 + 0x10 * ch, 1, 4, 0x01, 1, 0)
cats += category(50, txpdo)
cats += b'\xff\xff'
image = bytes(header) + cats
assert len(image) <= SIZE
image += b'\xff' * (SIZE - len(image))
print(image.hex().upper())
