#!/bin/sh
# check_png.sh FILE MIN_BYTES: FILE is a PNG (by its signature) of at least MIN_BYTES bytes.
sig=$(head -c 8 "$1" | od -An -tx1 | tr -d ' \n')
[ "$sig" = "89504e470d0a1a0a" ] || { echo "$1: not a PNG (signature '$sig')"; exit 1; }
size=$(wc -c < "$1")
[ "$size" -ge "$2" ] || { echo "$1: $size bytes, expected at least $2"; exit 1; }
echo "$1: PNG of $size bytes"
