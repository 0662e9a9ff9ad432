#!/usr/bin/env bash
# The hostile-input list, re-run against a build: each case prints its exit
# status, peak memory, wall time and first stderr line. Run from the
# repository root: bash docs/experiments/2026-12-06-hostile-inputs.sh
C="${CATGRAPH:-build/apps/catgraph}"; C="$(realpath "$C")"
sweep_config="$(realpath docs/experiments/manhattan-sweep.yaml)"
work="$(mktemp -d)"; cd "$work"
t() { local name="$1"; shift
  /usr/bin/time -f "%M %e" -o time.txt timeout 10 "$@" >out.txt 2>err.txt; local rc=$?
  read -r kb s < <(tail -1 time.txt)
  printf '%-44s rc=%-3s %5d MB %6s s | %s\n' "$name" "$rc" "$((kb/1024))" "$s" "$(grep -v '^\s*$' err.txt | head -1 | cut -c1-150)"
}
$C generate-graph --poses 60 -o g.g2o --truth truth.g2o >/dev/null
$C simulate --scenario office-change --frames 20 -o D --quiet >/dev/null
# 1 user files
mkdir -p U/images; for i in $(seq 1 500); do echo user > U/images/u$i.png; done
t "1 simulate into a user folder" $C simulate --scenario office-change -o U --frames 20 --quiet
echo "   user files left: $(ls U/images | grep -c '^u')"
# 2 output = input
cp g.g2o g0.g2o
t "2 optimize g -o g" $C optimize g.g2o -o g.g2o
t "2 optimize --report g" $C optimize g.g2o -o o.g2o --report g.g2o
t "2 inject -o g" $C inject g.g2o -o g.g2o --labels l.csv --outliers 3
t "2 inject --labels g" $C inject g.g2o -o i.g2o --labels g.g2o --outliers 3
t "2 generate-graph -o x --truth x" $C generate-graph -o x.g2o --truth x.g2o
t "2 vocabulary -o D/frames.csv" $C vocabulary train D -o D/frames.csv
t "2 plot-dataset -o D/images/000000.png" $C plot-dataset D -o D/images/000000.png
cmp -s g.g2o g0.g2o && echo "   g.g2o intact" || echo "   g.g2o CHANGED"
printf 'a,b\n1,2\n' > notsweep.csv; cp notsweep.csv ns0.csv
t "2 sweep -o a non-sweep csv" $C sweep --config "$sweep_config" -o notsweep.csv
cmp -s notsweep.csv ns0.csv && echo "   csv intact"
# 3 killed simulate over an existing dataset
cp -r D Dk; (timeout -s KILL 0.6 $C simulate --scenario office-change --frames 400 -o Dk --overwrite --quiet >/dev/null 2>&1)
echo "3 killed simulate: litter $(find . -name '*.tmp*' | wc -l); frames $(($(wc -l < Dk/frames.csv)-1))"
t "3 localize the killed-over dataset" $C localize Dk -o Lk --particles 200
# 4 bounds
printf 'a: &a ["x","x","x","x","x","x","x","x","x"]\nb: &b [*a,*a,*a,*a,*a,*a,*a,*a,*a]\nc: &c [*b,*b,*b,*b,*b,*b,*b,*b,*b]\nd: &d [*c,*c,*c,*c,*c,*c,*c,*c,*c]\ne: &e [*d,*d,*d,*d,*d,*d,*d,*d,*d]\nf: &f [*e,*e,*e,*e,*e,*e,*e,*e,*e]\ng: &g [*f,*f,*f,*f,*f,*f,*f,*f,*f]\nh: &h [*g,*g,*g,*g,*g,*g,*g,*g,*g]\n' > bomb.yaml
t "4 sweep alias bomb" $C sweep --config bomb.yaml -o r.csv
t "4 inject --outliers 2147483647" $C inject g.g2o -o i.g2o --outliers 2147483647
t "4 generate-graph --poses 100000" $C generate-graph --poses 100000 -o big.g2o
t "4 simulate --threads 2000" $C simulate --scenario office-change --frames 5 -o T --threads 2000 --quiet
t "4 localize --particles 2000000000" $C localize D -o L2 --particles 2000000000
# 5 symlinks
cp -r D S; rm S/images/000003.png; ln -s /etc/hostname S/images/000003.png
t "5 image symlinked outside" $C localize S -o LS --particles 200
cp -r D S2; mv S2/frames.csv S2/f.csv; ln -s /etc/passwd S2/frames.csv
t "5 frames.csv symlinked to /etc/passwd" $C localize S2 -o LS2
# 6 internal errors / hangs
cp -r D G; head -5 G/groundtruth.csv > G/gt && mv G/gt G/groundtruth.csv
t "6 short groundtruth: map" $C map G -o MG --particles 200
t "6 short groundtruth: sad-match" $C sad-match G -o SG
mkfifo fifo.g2o
t "6 FIFO input" $C optimize fifo.g2o -o o.g2o
# 7 silently wrong
$C inject g.g2o -o i.g2o --outliers 3 --labels l.csv >/dev/null; head -1 l.csv > lh.csv
$C optimize i.g2o -o oi.g2o >/dev/null
t "7 evaluate header-only labels" $C evaluate oi.g2o --truth truth.g2o --labels lh.csv
$C export truth.g2o -o truth.tum >/dev/null; (cat truth.tum; sed -n 5p truth.tum) > dup.tum
t "7 TUM with a duplicated row" $C evaluate oi.g2o --truth dup.tum
printf 'VERTEX_SE3:QUAT 0 0 0 0 1e300 0 0 1\nVERTEX_SE3:QUAT 1 1 0 0 0 0 0 1\nEDGE_SE3:QUAT 0 1 1 0 0 0 0 0 1 1 0 0 0 0 0 1 0 0 0 0 1 0 0 0 1 0 0 1 0 1\n' > q.g2o
t "7 quaternion 1e300" $C info q.g2o
# 8 hygiene
printf 'VERTEX_SE2 0 0 0 0\n\033[31mBAD\a 1 2\n' > esc.g2o
t "8 control bytes" $C info esc.g2o
grep -c $'\033' err.txt | sed 's/^/   raw ESC in stderr lines: /'
t "8 inject --outliers -1" $C inject g.g2o -o i.g2o --outliers -1
head -3 truth.g2o > t3.g2o
t "8 evaluate missing truth pose" $C evaluate g.g2o --truth t3.g2o
