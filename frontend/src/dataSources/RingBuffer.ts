/**
 * Fixed-capacity FIFO: pushing onto a full buffer drops the oldest item and
 * counts it. The store behind every live chart.
 *
 * @example
 *   const r = new RingBuffer<number>(2); r.push(1); r.push(2); r.push(3);
 *   r.toArray() // [2, 3]; r.dropped === 1
 */
export class RingBuffer<T> {
  private items: T[] = [];
  private start = 0;
  dropped = 0;

  constructor(readonly capacity: number) {
    if (capacity < 1) throw new Error("capacity must be at least 1");
  }

  get length(): number {
    return this.items.length;
  }

  push(item: T): void {
    if (this.items.length < this.capacity) {
      this.items.push(item);
      return;
    }
    this.items[this.start] = item;
    this.start = (this.start + 1) % this.capacity;
    this.dropped += 1;
  }

  /**
   * Puts an item where `key` orders it (the items are kept ascending by key):
   * pushed when it is not older than the last, else inserted in place, or put
   * in place of an item with the same key when `same` says it is the same one.
   * A full buffer drops its oldest item (which may be the new one) and counts it.
   */
  insertOrdered(item: T, key: (x: T) => number, same: (a: T, b: T) => boolean = () => false): void {
    const last = this.last();
    const k = key(item);
    if (last === undefined || key(last) < k) {
      this.push(item);
      return;
    }
    const all = this.toArray();
    let lo = 0;
    let hi = all.length;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (key(all[mid]) < k) lo = mid + 1;
      else hi = mid;
    }
    for (let i = lo; i < all.length && key(all[i]) === k; i++) {
      if (same(all[i], item)) {
        all[i] = item;
        this.items = all;
        this.start = 0;
        return;
      }
    }
    // Among equal keys, after the ones already there.
    while (lo < all.length && key(all[lo]) === k) lo++;
    all.splice(lo, 0, item);
    if (all.length > this.capacity) {
      all.shift();
      this.dropped += 1;
    }
    this.items = all;
    this.start = 0;
  }

  toArray(): T[] {
    return [...this.items.slice(this.start), ...this.items.slice(0, this.start)];
  }

  /** The newest item among the last `depth` that `pred` accepts (no copy of the buffer). */
  findLast(pred: (x: T) => boolean, depth = this.items.length): T | undefined {
    const n = this.items.length;
    for (let i = 1; i <= Math.min(depth, n); i++) {
      const x = this.items[(this.start + n - i) % n];
      if (pred(x)) return x;
    }
    return undefined;
  }

  last(): T | undefined {
    if (this.items.length === 0) return undefined;
    return this.items[(this.start + this.items.length - 1) % this.items.length];
  }
}
