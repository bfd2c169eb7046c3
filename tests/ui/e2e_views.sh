#!/bin/sh
# e2e_views.sh - the analysis views at 80x24: layout, spot, fan, OPD fan,
# wavefront map, FFT MTF, FFT PSF and encircled energy below
# the spreadsheet, chosen by the g key, drawn in braille within 80 columns,
# following an edit, coloured per wavelength (plain under NO_COLOR), and
# written by export as a PNG.  Output is TAP.
# Usage: e2e_views.sh PATH/TO/sagitta
#
# Independent reference: the spot radius on screen against "sagitta spot"
# run as a separate program on the same design, before and after the edit;
# the wavefront map's RMS against "sagitta wavefront" likewise.

SAGITTA=${1:-$SAGITTA}
. "$(dirname "$0")/tmuxlib.sh"
tmux_setup 15 views

cp "$ROOT/examples/cooke_triplet.json" "$WORK/cooke.json"

# Lines with a braille character (U+2800 to U+28FF: bytes E2 A0-A3 ..).
braille_lines() { screen | LC_ALL=C grep -c "$(printf '\342')[$(printf '\240\241\242\243')]"; }
# Lines wider than 80 characters (not bytes).
wide_lines() {
    screen | python3 -c 'import sys; print(sum(len(l.rstrip("\n")) > 80 for l in sys.stdin))'
}

# field 1's RMS radius in um from "sagitta spot", as the view shows it (%.4g).
spot_rms() {
    "$SAGITTA" spot "$1" --field 1 --format csv 2>/dev/null |
        awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "rms") k = i }
                 NR > 1 && $4 == "all" { printf "%.4g\n", $k * 1000 }'
}
screen_rms() { screen | grep -o "field 1: RMS [0-9.]*" | head -n 1 | sed 's/.* //'; }
# The wavefront view's RMS (piston and tilt removed, %.4g) of the ray's
# field, from "sagitta wavefront" at the view's 32-point grid.
wave_rms() {
    "$SAGITTA" wavefront "$1" --field "$2" --grid 32 --format json 2>/dev/null |
        python3 -c 'import json, sys; print("%.4g" % json.load(sys.stdin)["rms_centroid"])'
}
screen_wave_rms() { screen | grep -o "µm: RMS [0-9.e-]*" | head -n 1 | sed 's/.* //'; }

start cooke.json 80 24
if wait_for "cooke.json" 15 && wait_for "Surf"; then
    # 1. g: the layout, braille within 80 columns, the sheet still there.
    keys Escape g
    wait_for " layout " >/dev/null
    sleep 0.3
    WHY="braille lines $(braille_lines), lines over 80: $(wide_lines)"
    check "g shows the layout in braille at 80x24 beside the sheet" \
        sh -c "[ $(braille_lines) -ge 3 ] && [ $(wide_lines) -eq 0 ] &&
               $T capture-pane -p -t =main: | grep -q 'element 1' &&
               $T capture-pane -p -t =main: | grep -q 'z (mm)'"
    # 2. g again: the spot diagram, its RMS radius as sagitta spot's.
    keys Escape g
    wait_for "RMS" >/dev/null
    sleep 0.3
    R0=$(screen_rms)
    E0=$(spot_rms "$WORK/cooke.json")
    echo "# field 1 RMS: screen $R0 um, sagitta spot $E0 um"
    WHY="screen '$R0', sagitta spot '$E0'"
    check "the spot view's RMS radius is sagitta spot's" sh -c "[ -n '$R0' ] && [ '$R0' = '$E0' ]"
    # 3. Colour: wavelength colours on the view's rows.
    COL=$($T capture-pane -e -p -t =main: | tail -n 12 | grep -c "$(printf '\033')\[3[1-4]m")
    WHY="$COL coloured lines"
    check "the spot view is coloured per wavelength" sh -c "[ '$COL' -ge 2 ]"
    # 4. An edit: the view follows, to sagitta spot's value for the edited design.
    command_line "set 6 thickness 41.5"
    command_line "save $WORK/edited.json"
    wait_for "saved" >/dev/null
    sleep 0.5
    R1=$(screen_rms)
    E1=$(spot_rms "$WORK/edited.json")
    echo "# after the edit: screen $R1 um, sagitta spot $E1 um"
    WHY="before $R0, after: screen '$R1', sagitta spot '$E1'"
    check "after an edit the spot view shows the new design's RMS radius" \
        sh -c "[ -n '$R1' ] && [ '$R1' = '$E1' ] && [ '$R1' != '$R0' ]"
    # 5. g: the fans of the ray's field.
    keys Escape g
    wait_for "sagittal" >/dev/null
    sleep 0.3
    check "the fan view shows the tangential and sagittal fans" \
        sh -c "$T capture-pane -p -t =main: | grep -q tangential &&
               $T capture-pane -p -t =main: | grep -q sagittal && [ $(wide_lines) -eq 0 ]"
    # 6. export writes the view on show as a PNG of 1000 x 750.
    command_line "export $WORK/fan.png"
    wait_for "exported the fan view" >/dev/null
    W=$(od -An -tu1 -j16 -N8 "$WORK/fan.png" 2>/dev/null | awk '{ print $3 * 256 + $4, $7 * 256 + $8 }')
    WHY="PNG size '$W'"
    check "export FILE.png writes the view, 1000 x 750" sh -c "[ '$W' = '1000 750' ]"
    # 7. g: the OPD fans, in waves, within 80 columns.
    keys Escape g
    wait_for "OPD fans" >/dev/null
    sleep 0.3
    WHY="braille lines $(braille_lines), lines over 80: $(wide_lines)"
    check "the opd view shows OPD fans in waves" \
        sh -c "$T capture-pane -p -t =main: | grep -q 'W (waves)' &&
               $T capture-pane -p -t =main: | grep -q sagittal &&
               [ $(braille_lines) -ge 3 ] && [ $(wide_lines) -eq 0 ]"
    # 8. g: the wavefront map of the ray's field, its RMS as sagitta wavefront's.
    keys Escape g
    wait_for "Wavefront map" >/dev/null
    sleep 0.3
    FLD=$(screen | grep -o "field [0-9]* (" | tail -n 1 | sed 's/field \([0-9]*\).*/\1/')
    RW=$(screen_wave_rms)
    EW=$(wave_rms "$WORK/edited.json" "${FLD:-1}")
    echo "# wavefront field $FLD RMS: screen $RW, sagitta wavefront $EW waves"
    WHY="screen '$RW', sagitta wavefront '$EW', lines over 80: $(wide_lines)"
    check "the wave view shows the map, its RMS as sagitta wavefront's" \
        sh -c "[ -n '$RW' ] && [ '$RW' = '$EW' ] && [ $(wide_lines) -eq 0 ] &&
               $T capture-pane -p -t =main: | grep -q '█' &&
               $T capture-pane -p -t =main: | grep -q 'OPD .* waves'"
    # 8a. g: the FFT MTF of every field, with the diffraction limit.
    keys Escape g
    wait_for "FFT MTF" >/dev/null
    sleep 0.3
    WHY="braille lines $(braille_lines), lines over 80: $(wide_lines)"
    check "the mtf view draws the FFT MTF with its diffraction limit" \
        sh -c "$T capture-pane -p -t =main: | grep -q 'diffraction limit' &&
               $T capture-pane -p -t =main: | grep -q 'cycles/mm' &&
               [ $(braille_lines) -ge 3 ] && [ $(wide_lines) -eq 0 ]"
    # 8b. g: the FFT PSF's cross-sections of the ray's field.
    keys Escape g
    wait_for "PSF cross-sections" >/dev/null
    sleep 0.3
    WHY="braille lines $(braille_lines), lines over 80: $(wide_lines)"
    check "the psf view draws the PSF's cross-sections" \
        sh -c "[ $(braille_lines) -ge 3 ] && [ $(wide_lines) -eq 0 ]"
    # 8c. g: the encircled energy, exported as a PDF.
    keys Escape g
    wait_for "Encircled energy" >/dev/null
    sleep 0.3
    command_line "export $WORK/ee.pdf"
    wait_for "exported the encircled view" >/dev/null
    WHY="braille lines $(braille_lines), lines over 80: $(wide_lines), pdf: $(head -c 5 "$WORK/ee.pdf" 2>/dev/null)"
    check "the encircled view draws the energy and exports it" \
        sh -c "[ $(braille_lines) -ge 3 ] && [ $(wide_lines) -eq 0 ] &&
               [ \"\$(head -c 5 '$WORK/ee.pdf')\" = '%PDF-' ]"
    # 9. view off: the ray table is back.
    command_line "view off"
    wait_for "Surf status" >/dev/null
    check "view off brings back the results" sh -c "$T capture-pane -p -t =main: | grep -q 'Surf status'"
else
    not_ok "the Cooke triplet opens at 80x24"
    not_ok "spot"
    not_ok "colour"
    not_ok "edit"
    not_ok "fan"
    not_ok "export"
    not_ok "opd"
    not_ok "wave"
    not_ok "mtf"
    not_ok "psf"
    not_ok "encircled"
    not_ok "view off"
fi

# 10. NO_COLOR: the same view, no colour at all.
start cooke.json 80 24 "NO_COLOR=1"
if wait_for "cooke.json" 15 && wait_for "Surf"; then
    command_line "view spot"
    wait_for "RMS" >/dev/null
    sleep 0.3
    COL=$($T capture-pane -e -p -t =main: | grep -c "$(printf '\033')\[3[0-7]")
    WHY="$COL lines with colour"
    check "under NO_COLOR the spot view is monochrome" \
        sh -c "[ '$COL' -eq 0 ] && [ $(braille_lines) -ge 3 ]"
    # 11. The OPD fans under NO_COLOR: no colour either.
    command_line "view opd"
    wait_for "OPD fans" >/dev/null
    sleep 0.3
    COL=$($T capture-pane -e -p -t =main: | grep -c "$(printf '\033')\[3[0-7]")
    WHY="$COL lines with colour"
    check "under NO_COLOR the opd view is monochrome" \
        sh -c "[ '$COL' -eq 0 ] && [ $(braille_lines) -ge 3 ]"
else
    not_ok "NO_COLOR start"
    not_ok "NO_COLOR opd"
fi

# 12. The help screen names the view key.
keys Escape F1
wait_for "Help" >/dev/null
sleep 0.3
check "the help screen names g and :view" \
    sh -c "$T capture-pane -p -t =main: | grep -q 'g  *analysis view below the sheet'"

[ "$N" -eq "$NTESTS" ] || echo "# ran $N of $NTESTS"
[ "$FAILED" -eq 0 ]
