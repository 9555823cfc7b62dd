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

  toArray(): T[] {
    return [...this.items.slice(this.start), ...this.items.slice(0, this.start)];
  }

  last(): T | undefined {
    if (this.items.length === 0) return undefined;
    return this.items[(this.start + this.items.length - 1) % this.items.length];
  }
}
