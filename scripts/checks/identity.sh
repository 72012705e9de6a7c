#!/bin/bash
# usage: scripts/checks/identity.sh BIN OUTDIR [EXTRA_DIR]   -- run from a checkout root (reads tests/data, configs, data,
# and recordings of your own in EXTRA_DIR when given)
# Writes every observable output of BIN on the shipped files into OUTDIR; compare two OUTDIRs with diff -r.
B=$(readlink -f $1); O=$(readlink -f $2); rm -rf $O; mkdir -p $O/conv $O/sim $O/fit $O/misc
W=$(mktemp -d)
n=0
for f in $(find tests/data data ${3:+"$3"} -type f \( -name '*.csv' -o -name '*.tsv' -o -name '*.txt' -o -name '*.mcap' -o -name '*.h5' -o -name '*.xml' -o -name '*.trk' \) -not -path '*/fuzz/*' | sort); do
  k=$(echo $f | tr '/.' '__')
  $B convert $f $W/out.csv > $O/conv/$k.stdout 2> $O/conv/$k.stderr; echo $? > $O/conv/$k.rc
  $B inspect --json $f > $O/conv/$k.inspect.json 2> $O/conv/$k.inspect.stderr; echo $? > $O/conv/$k.inspect.rc
  [ -f $W/out.csv ] && mv $W/out.csv $O/conv/$k.csv
  n=$((n+1))
done
$B convert tests/data/tracker_slider.txt tests/data/tracker_bob.txt $W/out.csv > $O/conv/pair.stdout 2>&1; echo $? >> $O/conv/pair.stdout; mv $W/out.csv $O/conv/pair.csv
$B convert --t-end 0.5 data/example_recording.mcap $W/out.csv > $O/conv/tend.stdout 2>&1; mv $W/out.csv $O/conv/tend.csv
for f in $(find configs tests/data -name '*.toml' | sort); do
  k=$(echo $f | tr '/.' '__')
  $B simulate --json $f > $O/sim/$k.json 2> $O/sim/$k.stderr; echo $? > $O/sim/$k.rc
  $B simulate $f --out $W/sim.csv > $O/sim/$k.txt 2>&1; [ -f $W/sim.csv ] && mv $W/sim.csv $O/sim/$k.csv
done
$B fit data/example_recording.mcap --rig configs/rig_example.toml --json > $O/fit/example.json 2>&1
for r in light paper heavy; do for k in measured lab; do
$B fit tests/data/rigid/rigid_$r.csv --rig tests/data/rigid/rigid_${r}_$k.toml --json > $O/fit/rigid_${r}_$k.json 2>&1
done; done
$B fit tests/data/tracker_slider.txt tests/data/tracker_bob.txt --rig configs/markers_example.toml --robust huber --json > $O/fit/tracker.json 2>&1
$B fit tests/data/misspec/drag_paper.csv --rig tests/data/misspec/paper_measured.toml > $O/fit/drag_paper.txt 2>&1
$B fit data/campaign --joint --rig data/campaign/rig_measured.toml --json > $O/fit/joint.json 2>&1
$B fit data/example_recording.mcap --rig configs/rig_example.toml > $O/fit/example.txt 2>&1
$B plan configs/plan_example.toml --json > $O/misc/plan.json 2>&1
$B plan configs/plan_example.toml --plot $W/plan.svg > $O/misc/plan.txt 2>&1; mv $W/plan.svg $O/misc/
$B regions configs/rig_paper.toml --json > $O/misc/regions.json 2>&1
$B regions configs/rig_paper.toml --plot $W/regions.svg > $O/misc/regions.txt 2>&1; mv $W/regions.svg $O/misc/
$B fit data/example_recording.mcap --rig configs/rig_example.toml --plot $W/fit.svg > /dev/null 2>&1; mv $W/fit.svg $O/misc/
$B synth configs/paper_rest_horizontal.toml $W/s.csv --noise 0.001 --seed 3 > $O/misc/synth.txt 2>&1; mv $W/s.csv $O/misc/ 2>/dev/null
$B synth configs/paper_rest_horizontal.toml $W/s.mcap --noise 0.001 --seed 3 >> $O/misc/synth.txt 2>&1; mv $W/s.mcap $O/misc/ 2>/dev/null
grep -rl "$W" $O | xargs -r sed -i "s|$W|WORK|g"
rm -rf $W
echo "files converted: $n"
